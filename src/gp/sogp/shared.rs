//! A model whose BVs' distinct inputs are held in its learner's [`SharedInputs`], with the
//! other experts that observe the same input stream, instead of a table of its own.
//!
//! The shared table computes each new input's distances once per step for all of them;
//! a model reads its (BV, lag) distances from it through its own index, as it would from
//! its own table: the same numbers, so every kernel value is bit-identical. Only the
//! learner's calls (`observe_in`, `update_in`) lend the shared table to the model; any
//! other call first gives the model a table of its own again, rebuilt from its BVs (a
//! copy of an expert taken out of its learner goes on as it would have).

use super::super::inputs::shared::SharedInputs;
use super::super::inputs::{Table, own_table_start};
use super::super::window::Stamp;
use super::Sogp;

impl Sogp {
    /// True if the model can read its distances from `shared`: no adaptation, and every
    /// hyperparameter equal to the bit (see [`SharedInputs::fits`]).
    pub(crate) fn fits(&self, shared: &SharedInputs) -> bool {
        shared.fits(
            &self.kernel,
            self.adaptation_params.is_some() || self.adapt.is_some(),
        )
    }

    /// True while the model's inputs are held in a shared table.
    pub fn shares_inputs(&self) -> bool {
        self.inputs.shared
    }

    /// Hold the BVs' inputs in `shared` instead of a table of its own (a model joins one
    /// shared table, once). Returns whether it does: a model that does not fit keeps its
    /// own.
    pub(crate) fn join(&mut self, shared: &mut SharedInputs) -> bool {
        if self.inputs.shared {
            return true;
        }
        if !self.fits(shared) {
            return false;
        }
        let (dim, tau) = (self.kernel.dim(), self.kernel.tau());
        self.inputs.set_table(Table::new(dim, tau, 0));
        self.inputs.shared = true;
        self.lend(shared, Sogp::add_every_bv);
        // The shared rows may be of another window than the one this model observed.
        self.x_stamp = None;
        true
    }

    /// A table of its own again, rebuilt from the BVs (the shared one is not touched).
    pub(super) fn own_inputs(&mut self) {
        if !self.inputs.shared {
            return;
        }
        self.inputs.shared = false;
        self.rebuild_inputs(self.own_table());
    }

    /// An empty table of the model's own, sized as a new model's.
    pub(super) fn own_table(&self) -> Table {
        let tau = self.kernel.tau();
        Table::new(self.kernel.dim(), tau, own_table_start(self.stride, tau))
    }

    /// Hold the BVs' inputs in `table` from now on, every BV stored there again. The table
    /// has no rows yet: the next observation computes (or looks up) them all.
    pub(super) fn rebuild_inputs(&mut self, table: Table) {
        self.inputs.set_table(table);
        self.add_every_bv();
        self.x_stamp = None;
        self.observed = None;
    }

    /// Put every BV's inputs in the table the model holds now (its own, or a lent one).
    pub(super) fn add_every_bv(&mut self) {
        let w = self.wlen;
        let inv_rho = 1.0 / self.kernel.params().sigma_rho;
        for i in 0..self.n {
            let (raw, scaled) = (
                &self.bv_raw[i * w..(i + 1) * w],
                &self.bv_scaled[i * w..(i + 1) * w],
            );
            self.inputs.add_bv(i, raw, scaled, inv_rho);
        }
    }

    /// Run `f` with the shared table in place of the model's stand-in.
    fn lend<R>(&mut self, shared: &mut SharedInputs, f: impl FnOnce(&mut Sogp) -> R) -> R {
        std::mem::swap(&mut self.inputs.table, &mut shared.table);
        let r = f(self);
        std::mem::swap(&mut self.inputs.table, &mut shared.table);
        r
    }

    /// [`Sogp::observe_window`] at the window `window` stamped `stamp`: the shared rows
    /// are made those of the window (once for all the models that share them) and the
    /// model evaluates from them. A model that did not join observes on its own.
    pub(crate) fn observe_in(&mut self, shared: &mut SharedInputs, window: &[f64], stamp: Stamp) {
        if self.inputs.shared {
            shared.observe(window, Some(stamp));
            let shift = self.shift_to(stamp);
            self.take_window(shift, window, stamp);
            // Without adaptation no gradient reads K_t per lag.
            self.lend(shared, |m| m.evaluate_keeping(false));
        } else {
            self.observe_stamped(window, stamp);
        }
    }

    /// [`Sogp::update`] of a model that joined `shared` (its inputs change there). If the
    /// model must be evaluated again and the shared rows are of another window than the
    /// one it observed last, they are made those of its window first.
    pub(crate) fn update_in(&mut self, shared: &mut SharedInputs, y: &[f64]) {
        if !self.inputs.shared {
            self.update(y);
            return;
        }
        if self.observed != Some(self.version)
            && (self.x_stamp.is_none() || self.x_stamp != shared.stamp)
        {
            shared.observe(&self.x_raw, self.x_stamp);
        }
        self.lend(shared, |m| m.learn(y));
    }

    /// Distinct inputs the BVs hold (each counted once however many BVs hold it).
    pub fn distinct_inputs(&self) -> usize {
        self.inputs.distinct_of(self.n)
    }
}
