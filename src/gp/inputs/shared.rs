//! One distance table for the models of a learner that observe one input stream with the
//! same hyperparameters to the bit.

use super::super::kernel::RecursiveArd;
use super::super::window::Stamp;
use super::{Shift, Table};

/// One [`Table`] for the models of a learner that observe one input stream with
/// bit-identical kernel hyperparameters and no adaptation (so that they stay identical):
/// the squared distances of an input to another are then the same number for every model,
/// so each new input's distances are computed once per step instead of once per model.
/// Each model keeps its own (BV, lag) → slot index and padding prefixes.
#[derive(Clone, Debug)]
pub(crate) struct SharedInputs {
    kernel: RecursiveArd,
    pub(in crate::gp) table: Table,
    /// The stamp of the window the rows are for.
    pub(in crate::gp) stamp: Option<Stamp>,
}

impl SharedInputs {
    /// A table for models with `kernel`'s hyperparameters.
    pub(crate) fn new(kernel: &RecursiveArd) -> SharedInputs {
        SharedInputs {
            kernel: kernel.clone(),
            table: Table::new(kernel.dim(), kernel.tau(), 0),
            stamp: None,
        }
    }

    /// True if a model with `kernel` reads the same distances from this table as from its
    /// own: the same dimensions, every hyperparameter equal to the bit, and (`adapts`
    /// false) no adaptation that could change them.
    pub(crate) fn fits(&self, kernel: &RecursiveArd, adapts: bool) -> bool {
        let (a, b) = (self.kernel.params(), kernel.params());
        let same = |x: f64, y: f64| x.to_bits() == y.to_bits();
        !adapts
            && self.kernel.dim() == kernel.dim()
            && self.kernel.tau() == kernel.tau()
            && a.lengthscales.len() == b.lengthscales.len()
            && a.lengthscales
                .iter()
                .zip(&b.lengthscales)
                .all(|(x, y)| same(*x, *y))
            && same(a.sigma_rho, b.sigma_rho)
            && same(a.sigma_f, b.sigma_f)
            && same(a.sigma_n, b.sigma_n)
    }

    /// The rows made those of `window` stamped `stamp` (None: unknown, every row again).
    pub(crate) fn observe(&mut self, window: &[f64], stamp: Option<Stamp>) {
        let shift = match (self.stamp, stamp) {
            (Some(a), Some(b)) if a == b => Shift::Same,
            (Some(a), Some(b)) if b.follows(a) => Shift::ByOne,
            _ => Shift::Other,
        };
        // A shared table holds its inputs itself, so every window is observed.
        let held = self.table.observe(&self.kernel, shift, window);
        debug_assert!(held);
        self.stamp = stamp;
    }

    /// Distinct inputs held by the models' BVs.
    pub(crate) fn distinct(&self) -> usize {
        self.table.distinct()
    }
}
