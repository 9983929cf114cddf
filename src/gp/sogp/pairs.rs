//! A model whose distance rows and kernel vectors are read from a session's
//! [`PairDistances`] instead of computed.
//!
//! The model's BV lags then point at the pair table's inputs, an observed window's rows
//! are the pair table's rows of its inputs, and its kernel vector the window's row of
//! window kernels (when the table holds the window and every BV's, for the model's
//! sigma_rho): the same numbers, so every kernel value is bit-identical. It holds while
//! every window the model observes is made of the pair table's inputs and its lengthscales
//! are the table's: at a window with another input, and before its hyperparameters change,
//! the model goes on with a table of its own, rebuilt from its BVs.

use std::sync::Arc;

use super::super::inputs::{Shift, Table, own_table_start};
use super::super::pairs::PairDistances;
use super::Sogp;

impl Sogp {
    /// Read the distances from `pairs` from now on, if its lengthscales are the model's
    /// and it holds every input of the BVs and of the window observed last. Returns
    /// whether the model does. A model in a learner's shared table stays there.
    pub fn use_pairs(&mut self, pairs: &Arc<PairDistances>) -> bool {
        if self.inputs.shared || !pairs.fits(&self.kernel) {
            return false;
        }
        let d = self.kernel.dim();
        let held = |w: &[f64]| w.chunks_exact(d).all(|x| pairs.id(x).is_some());
        if !held(&self.x_raw) || !held(&self.bv_raw[..self.n * self.wlen]) {
            return false;
        }
        let tau = self.kernel.tau();
        let slots = own_table_start(self.stride, tau);
        self.rebuild_inputs(Table::over(pairs.clone(), tau, slots));
        true
    }

    /// True while the distances are read from a session's pair table.
    pub fn reads_pairs(&self) -> bool {
        self.inputs.over_pairs()
    }

    /// A table of its own again, rebuilt from the BVs, if the model reads a pair table.
    pub(super) fn leave_pairs(&mut self) {
        if !self.inputs.over_pairs() {
            return;
        }
        self.rebuild_inputs(self.own_table());
    }

    /// The distance rows made those of `window` (standing to the window observed last as
    /// `shift` says); a window with an input the pair table does not hold makes the model
    /// leave it first.
    pub(super) fn observe_inputs(&mut self, shift: Shift, window: &[f64]) {
        if !self.inputs.observe(&self.kernel, shift, window) {
            self.leave_pairs();
            let own = self.inputs.observe(&self.kernel, Shift::Other, window);
            debug_assert!(own);
        }
    }
}
