//! The distinct inputs held by a model's BV windows, and the squared distances of the
//! observed window's lags to them.
//!
//! Consecutive windows of a sequence share tau − 1 inputs: the BVs a model keeps from one
//! grasp hold each of its inputs at up to tau lags, and the windows observed along a
//! sequence shift by one input per step. The recursive kernel needs, at every lag, the
//! distance between the window's input there and the BV's input there. Stored once per
//! distinct input, with each BV lag pointing at its input, a step computes the distances
//! of the one new input of the window to the distinct inputs, and each (BV, lag) only looks
//! its distance up: a fraction of the tau·n distances of a direct evaluation. The
//! distances are those [`super::kernel::sq_dist`] gives for the pair, so the kernel values
//! are bit-identical to [`super::RecursiveArd::unit_many`].
//!
//! The models of a learner that observe one input stream with the same hyperparameters to
//! the bit (no adaptation) can hold their distinct inputs in one [`SharedInputs`](shared::SharedInputs): each
//! new input's distances are then computed once per step for all of them.
//!
//! A model whose windows are all a known session's (a clustering sweep) can hold its
//! inputs over the session's [`PairDistances`] instead: its rows are then copied from there
//! when read, and its kernel vector read from the observed window's row of window kernels.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;
use std::sync::Arc;

use super::bits::{Prehashed, hash_bits, same_bits};
use super::kernel::{LANES, LagMajor, RecursiveArd, exp_nonpos};
use super::pairs::{NO_WINDOW, PairDistances};
use super::wide::dispatch_wide;

pub(crate) mod shared;

/// The distinct inputs of BV windows and the distances of the observed window's lags to
/// them: one model's own (computed, or copied from a pair table), or held once for the
/// models of a learner ([`SharedInputs`](shared::SharedInputs)).
#[derive(Clone, Debug)]
pub(crate) struct Table {
    dim: usize,
    tau: usize,
    /// Input slots (twice as many once every one is taken).
    slots: usize,
    /// Scaled inputs (one lag each), blocked for the many-input distance.
    data: LagMajor,
    /// Raw input of every slot (`dim` values each), to tell equal inputs apart from a
    /// collision of their hashes.
    raw: Vec<f64>,
    refs: Vec<u32>,
    free: Vec<u32>,
    /// Slots ever used (the rows cover 0..used).
    used: usize,
    /// Hash of a raw input → its slot.
    lookup: HashMap<u64, u32, BuildHasherDefault<Prehashed>>,
    /// Leading padding lags of the observed window.
    lead: usize,
    /// Distances of the observed window's lags to every slot: tau rows of `slots`, lag l
    /// in row (head + l) mod tau; the rows of the leading padding lags are stale.
    rows: Vec<f64>,
    head: usize,
    /// The observed window's lags, scaled, in the rows' order (lag l at (head + l) mod tau).
    seen: Vec<f64>,
    /// The rows belong to the window last given to [`Table::observe`] and the stored
    /// inputs.
    current: bool,
    /// A session's pair table that holds every input here: the rows are then copied from
    /// its rows, when first read, instead of computed (boxed: a shared table is swapped
    /// in and out of its models at every step).
    pub(super) paired: Option<Box<Paired>>,
}

/// The pair table a [`Table`] copies its rows from, and where its inputs are there.
#[derive(Clone, Debug)]
pub(super) struct Paired {
    pairs: Arc<PairDistances>,
    /// Each slot's input.
    pid: Vec<u32>,
    /// Each row's input (every lag's, the padding ones too).
    row_of: Vec<u32>,
    /// The input each row was copied for (the copy holds every used slot).
    rows_for: Vec<u32>,
    /// The observed window ([`NO_WINDOW`] if not held).
    window: u32,
    /// The observed window's input ids in lag order, to look the window up.
    ids: Vec<u32>,
}

/// A row copied for no input.
const NO_ROW: u32 = u32::MAX;

/// The inputs of one model's BVs: where each (BV, lag) input is in a [`Table`], and the
/// table itself (the model's own, or a stand-in while a learner's shared one serves it).
#[derive(Clone, Debug)]
pub(crate) struct Inputs {
    tau: usize,
    /// BV slots per lag in `index` (the models' lane stride).
    lanes: usize,
    /// Input slot of BV i at lag l: `index[l * lanes + i]`.
    index: Vec<u32>,
    /// K_t of BV i after t = l + 1 padding lags (all-zero inputs, as at the start of a
    /// sequence): `prefix[l * lanes + i]`. It depends on the BV alone.
    prefix: Vec<f64>,
    /// Over a pair table, BV i's window there ([`NO_WINDOW`] if not held): `window[i]`.
    window: Vec<u32>,
    pub(super) table: Table,
    /// The BVs' inputs are in a [`SharedInputs`](shared::SharedInputs); `table` is an empty stand-in, swapped
    /// with the shared table for the calls that read it.
    pub(super) shared: bool,
}

/// How an observed window stands to the one observed before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Shift {
    Same,
    /// The earlier window shifted by one input.
    ByOne,
    Other,
}

impl Shift {
    /// The shift between two windows of `dim` inputs per lag, found by comparing them.
    /// Equal as numbers is enough: ±0 give the same distances, and NaN recomputes.
    pub(crate) fn between(previous: &[f64], window: &[f64], dim: usize) -> Shift {
        if previous == window {
            Shift::Same
        } else if previous[dim..] == window[..window.len() - dim] {
            Shift::ByOne
        } else {
            Shift::Other
        }
    }
}

impl Table {
    /// Room for `slots` inputs of `dim` values, over `tau` lags.
    pub(crate) fn new(dim: usize, tau: usize, slots: usize) -> Table {
        let data = LagMajor::new(dim, 1, slots);
        let slots = data.stride();
        Table {
            dim,
            tau,
            slots,
            data,
            raw: vec![0.0; slots * dim],
            refs: vec![0; slots],
            free: Vec::new(),
            used: 0,
            lookup: HashMap::default(),
            lead: 0,
            rows: vec![0.0; tau * slots],
            head: 0,
            seen: vec![0.0; tau * dim],
            current: false,
            paired: None,
        }
    }

    /// Room for `slots` inputs of `pairs` (for `tau` lags), whose rows are copied from it.
    pub(crate) fn over(pairs: Arc<PairDistances>, tau: usize, slots: usize) -> Table {
        let table = Table::new(pairs.dim(), tau, slots);
        Table {
            paired: Some(Box::new(Paired {
                pid: vec![0; table.slots],
                row_of: vec![0; tau],
                rows_for: vec![NO_ROW; tau],
                window: NO_WINDOW,
                ids: vec![0; tau],
                pairs,
            })),
            ..table
        }
    }

    /// Forget every input and the distance rows.
    fn clear(&mut self) {
        if let Some(p) = self.paired.as_mut() {
            p.rows_for.fill(NO_ROW);
        }
        self.refs.fill(0);
        self.free.clear();
        self.used = 0;
        self.lookup.clear();
        self.current = false;
    }

    /// Inputs held by at least one BV.
    pub(crate) fn distinct(&self) -> usize {
        self.used - self.free.len()
    }

    /// The slot of one raw input (scaled `scaled`), stored if new, with its distances to
    /// the observed lags while the rows are current; one more reference.
    #[inline(always)]
    fn acquire(&mut self, raw: &[f64], scaled: &[f64]) -> usize {
        let h = hash_bits(raw);
        if let Some(&j) = self.lookup.get(&h) {
            let j = j as usize;
            if same_bits(&self.raw[j * self.dim..(j + 1) * self.dim], raw) {
                self.refs[j] += 1;
                return j;
            }
        }
        let j = match self.free.pop() {
            Some(j) => j as usize,
            None => {
                // Every slot is taken: twice the room (a model's own table starts at
                // OWN_TABLE_START, as most models hold far fewer inputs than they could).
                if self.used == self.slots {
                    self.grow(2 * self.slots);
                }
                self.used += 1;
                self.used - 1
            }
        };
        self.raw[j * self.dim..(j + 1) * self.dim].copy_from_slice(raw);
        self.refs[j] = 1;
        // On a hash collision the earlier input keeps the entry; this one is only unshared.
        self.lookup.entry(h).or_insert(j as u32);
        match self.paired.as_mut() {
            Some(p) => {
                // A model leaves the pair table at the first window with an input it does
                // not hold, and a BV is an observed window.
                let id = p
                    .pairs
                    .id_hashed(h, raw)
                    .expect("a BV input of the pair table");
                p.pid[j] = id;
                for (r, &a) in p.rows_for.iter().enumerate() {
                    if a != NO_ROW {
                        self.rows[r * self.slots + j] = p.pairs.row(a)[id as usize];
                    }
                }
            }
            None => {
                self.data.set(j, scaled);
                if self.current {
                    let d = self.dim;
                    for r in 0..self.tau {
                        let x = &self.seen[r * d..(r + 1) * d];
                        self.rows[r * self.slots + j] = super::kernel::sq_dist(x, scaled);
                    }
                }
            }
        }
        j
    }

    /// One reference fewer to slot `j`; freed when no BV holds it any more.
    fn release(&mut self, j: usize) {
        self.refs[j] -= 1;
        if self.refs[j] == 0 {
            let h = hash_bits(&self.raw[j * self.dim..(j + 1) * self.dim]);
            if self.lookup.get(&h) == Some(&(j as u32)) {
                self.lookup.remove(&h);
            }
            self.free.push(j as u32);
        }
    }

    /// Room for `slots` inputs: the inputs, their slots and the rows are kept.
    fn grow(&mut self, slots: usize) {
        let (d, old) = (self.dim, self.slots);
        self.data.grow_single_lag(slots);
        self.slots = self.data.stride();
        self.raw.resize(self.slots * d, 0.0);
        self.refs.resize(self.slots, 0);
        if let Some(p) = self.paired.as_mut() {
            p.pid.resize(self.slots, 0);
        }
        let mut rows = vec![0.0; self.tau * self.slots];
        for (to, from) in rows
            .chunks_exact_mut(self.slots)
            .zip(self.rows.chunks_exact(old))
        {
            to[..self.used].copy_from_slice(&from[..self.used]);
        }
        self.rows = rows;
    }

    /// Make the rows those of `window` (raw, oldest lag first), which stands to the window
    /// they were computed for as `shift` says: nothing for the same window, one new row for
    /// that window shifted by one input, else every row past the leading padding lags.
    /// False (the rows are then of no window) if the table is over a pair table that does
    /// not hold an input of the window.
    #[must_use]
    pub(crate) fn observe(&mut self, kernel: &RecursiveArd, shift: Shift, window: &[f64]) -> bool {
        let (d, tau) = (self.dim, self.tau);
        if self.current {
            match shift {
                Shift::Same => return true,
                Shift::ByOne => {
                    self.head = (self.head + 1) % tau;
                    let newest = &window[(tau - 1) * d..];
                    if !self.fill_row(kernel, tau - 1, newest) {
                        return false;
                    }
                    self.lead = match self.lead {
                        l if l == tau => tau - 1 + usize::from(newest.iter().all(|v| *v == 0.0)),
                        l => l.saturating_sub(1),
                    };
                    self.find_window(kernel);
                    return true;
                }
                Shift::Other => {}
            }
        }
        self.lead = window
            .chunks_exact(d)
            .take_while(|l| l.iter().all(|v| *v == 0.0))
            .count();
        // The leading padding lags take the BVs' prefixes: their rows are never read (and
        // stay padding until they leave the window), so only the later ones are filled.
        // Over a pair table the padding lags are looked up too, so that every input of the
        // window (a BV to be) is known to be held.
        if self.paired.is_some() {
            for lag in 0..self.lead {
                if !self.look_up(lag, &window[lag * d..(lag + 1) * d]) {
                    return false;
                }
            }
        }
        for lag in self.lead..tau {
            if !self.fill_row(kernel, lag, &window[lag * d..(lag + 1) * d]) {
                return false;
            }
        }
        self.find_window(kernel);
        self.current = true;
        true
    }

    /// Over a pair table, the observed window's id there (under `kernel`'s recursion).
    fn find_window(&mut self, kernel: &RecursiveArd) {
        let Some(p) = self.paired.as_mut() else {
            return;
        };
        for (lag, id) in p.ids.iter_mut().enumerate() {
            *id = p.row_of[(self.head + lag) % self.tau];
        }
        p.window = p.pairs.window(&p.ids, 1.0 / kernel.params().sigma_rho);
    }

    /// Copy the rows of the observed window's lags past the leading padding that are not
    /// copied for their input yet (a table of its own computes its rows as it observes).
    fn ensure_rows(&mut self) {
        let Some(p) = self.paired.as_deref_mut() else {
            return;
        };
        for lag in self.lead..self.tau {
            let r = (self.head + lag) % self.tau;
            if p.rows_for[r] != p.row_of[r] {
                let m = self.used.div_ceil(LANES) * LANES;
                copy_row(p, r, &mut self.rows[r * self.slots..r * self.slots + m]);
            }
        }
    }

    /// Over a pair table, note that the input of lag `lag` is its input `x`; false (the
    /// rows then current for no window) if the pair table does not hold `x`.
    fn look_up(&mut self, lag: usize, x: &[f64]) -> bool {
        let Some(p) = self.paired.as_mut() else {
            return true;
        };
        match p.pairs.id(x) {
            Some(a) => {
                p.row_of[(self.head + lag) % self.tau] = a;
                true
            }
            None => {
                self.current = false;
                false
            }
        }
    }

    /// Row of lag `lag`: the distances of the raw input `x` to every used slot, computed
    /// (over a pair table, only its input noted: the row is copied when first read); false
    /// as [`Table::look_up`].
    fn fill_row(&mut self, kernel: &RecursiveArd, lag: usize, x: &[f64]) -> bool {
        if self.paired.is_some() {
            return self.look_up(lag, x);
        }
        self.compute_row(kernel, lag, x);
        true
    }

    fn compute_row(&mut self, kernel: &RecursiveArd, lag: usize, x: &[f64]) {
        dispatch_wide!(["avx512f", "avx2"] Table::fill_row_portable, (
            this: &mut Table = self,
            kernel: &RecursiveArd = kernel,
            lag: usize = lag,
            x: &[f64] = x,
        ))
    }

    #[inline(always)]
    fn fill_row_portable(&mut self, kernel: &RecursiveArd, lag: usize, x: &[f64]) {
        let r = (self.head + lag) % self.tau;
        let seen = &mut self.seen[r * self.dim..(r + 1) * self.dim];
        kernel.scale_into(x, seen);
        let m = self.used.div_ceil(LANES) * LANES;
        let at = r * self.slots;
        self.data
            .lag_sq_dist(0, seen, m, &mut self.rows[at..at + m]);
    }

    /// The distances of the observed window's lag `lag` to every slot.
    #[inline(always)]
    fn row(&self, lag: usize) -> &[f64] {
        let r = (self.head + lag) % self.tau;
        &self.rows[r * self.slots..(r + 1) * self.slots]
    }

    /// Squared norm of slot `j`'s input (its distance to a padding lag).
    #[inline(always)]
    fn norm(&self, j: usize) -> f64 {
        match &self.paired {
            Some(p) => p.pairs.norm(p.pid[j]),
            None => self.data.norm(0, j),
        }
    }
}

/// Row `r` of a table over `p` (its used slots, `row`) copied from the pair table's row of
/// its input.
fn copy_row(p: &mut Paired, r: usize, row: &mut [f64]) {
    dispatch_wide!(["avx512f", "avx2"] copy_row_portable, (
        p: &mut Paired = p,
        r: usize = r,
        row: &mut [f64] = row,
    ))
}

#[inline(always)]
fn copy_row_portable(p: &mut Paired, r: usize, row: &mut [f64]) {
    let from = p.pairs.row(p.row_of[r]);
    for (d, &j) in row.iter_mut().zip(&p.pid) {
        // `get`: a gather (every slot's input is one of the pair table's).
        *d = from.get(j as usize).copied().unwrap_or(f64::NAN);
    }
    p.rows_for[r] = p.row_of[r];
}

/// Input slots a model's own table starts with (it grows as it fills): its BVs could hold
/// tau inputs each, but consecutive BV windows of a sequence share all but one.
const OWN_TABLE_START: usize = 128;

/// The slots a model's own table starts with, for `bv_slots` BVs of `tau` lags.
pub(crate) fn own_table_start(bv_slots: usize, tau: usize) -> usize {
    (bv_slots * tau).min(OWN_TABLE_START)
}

impl Inputs {
    /// Room for `bv_slots` BVs of `tau` lags of `dim` inputs; `lanes` is the BV stride of
    /// the kernel buffers (a multiple of [`LANES`], at least `bv_slots`).
    pub(crate) fn new(dim: usize, tau: usize, bv_slots: usize, lanes: usize) -> Inputs {
        Inputs {
            tau,
            lanes,
            index: vec![0; tau * lanes],
            prefix: vec![0.0; tau * lanes],
            window: vec![NO_WINDOW; lanes],
            table: Table::new(dim, tau, own_table_start(bv_slots, tau)),
            shared: false,
        }
    }

    /// Forget every input and the distance rows (the BVs are about to be stored again).
    pub(crate) fn clear(&mut self) {
        debug_assert!(
            !self.shared,
            "a shared table is cleared only by its learner"
        );
        self.table.clear();
    }

    /// Store BV `i` (raw and scaled window, oldest lag first) of a kernel with recursion
    /// divisor 1/`inv_rho`. While the rows are current, a new input's distances to the
    /// observed lags are added to them.
    pub(crate) fn add_bv(&mut self, i: usize, raw: &[f64], scaled: &[f64], inv_rho: f64) {
        // Wide vectors for the new input's distances and the prefixes' exponentials (the
        // same operations in the same order, so the same bits).
        dispatch_wide!(["avx512f", "avx2"] Inputs::add_bv_portable, (
            this: &mut Inputs = self,
            i: usize = i,
            raw: &[f64] = raw,
            scaled: &[f64] = scaled,
            inv_rho: f64 = inv_rho,
        ))
    }

    #[inline(always)]
    fn add_bv_portable(&mut self, i: usize, raw: &[f64], scaled: &[f64], inv_rho: f64) {
        let d = self.table.dim;
        let mut k = 1.0;
        for lag in 0..self.tau {
            let (r, s) = (
                &raw[lag * d..(lag + 1) * d],
                &scaled[lag * d..(lag + 1) * d],
            );
            let j = self.table.acquire(r, s);
            self.index[lag * self.lanes + i] = j as u32;
            // As the recursion runs at a padding lag: the distance is the input's norm.
            k = exp_nonpos(-0.5 * self.table.norm(j) + (k - 1.0) * inv_rho);
            self.prefix[lag * self.lanes + i] = k;
        }
        if let Some(p) = self.table.paired.as_deref_mut() {
            for (lag, id) in p.ids.iter_mut().enumerate() {
                *id = p.pid[self.index[lag * self.lanes + i] as usize];
            }
            self.window[i] = p.pairs.window(&p.ids, inv_rho);
        }
    }

    /// Drop BV `i`'s references; inputs no BV holds any more are freed.
    pub(crate) fn release_bv(&mut self, i: usize) {
        for lag in 0..self.tau {
            self.table
                .release(self.index[lag * self.lanes + i] as usize);
        }
    }

    /// Move BV `from`'s inputs and prefixes into slot `to` (whose BV was released).
    pub(crate) fn move_bv(&mut self, from: usize, to: usize) {
        for lag in 0..self.tau {
            self.index[lag * self.lanes + to] = self.index[lag * self.lanes + from];
            self.prefix[lag * self.lanes + to] = self.prefix[lag * self.lanes + from];
        }
        self.window[to] = self.window[from];
    }

    /// The table's rows made those of `window` (see [`Table::observe`]).
    #[must_use]
    pub(crate) fn observe(&mut self, kernel: &RecursiveArd, shift: Shift, window: &[f64]) -> bool {
        self.table.observe(kernel, shift, window)
    }

    /// Hold the inputs in `table` from now on (the BVs are about to be stored again): the
    /// slots of the lanes past the BVs, read but ignored, are made slots of the new table.
    pub(crate) fn set_table(&mut self, table: Table) {
        self.table = table;
        self.index.fill(0);
        self.window.fill(NO_WINDOW);
    }

    /// True while the inputs are those of a session's pair table.
    pub(crate) fn over_pairs(&self) -> bool {
        self.table.paired.is_some()
    }

    /// Distinct inputs held by BVs 0..n (with those of other models, in a shared table).
    pub(crate) fn distinct_of(&self, n: usize) -> usize {
        let mut slots: Vec<u32> = (0..self.tau)
            .flat_map(|l| {
                self.index[l * self.lanes..l * self.lanes + n]
                    .iter()
                    .copied()
            })
            .collect();
        slots.sort_unstable();
        slots.dedup();
        slots.len()
    }

    /// Unit K_tau between the observed window and BVs 0..n, as
    /// [`RecursiveArd::unit_many`] gives it (bit for bit), from the distance rows: K_t
    /// per lag into `lag_k` (tau rows of `lanes`), K_tau into `out`. Lanes past n hold
    /// values of stale slots.
    pub(crate) fn unit_many(&mut self, inv_rho: f64, n: usize, lag_k: &mut [f64], out: &mut [f64]) {
        self.table.ensure_rows();
        dispatch_wide!(["avx512f", "avx2"] Inputs::unit_many_portable, (
            this: &Inputs = self,
            inv_rho: f64 = inv_rho,
            n: usize = n,
            lag_k: &mut [f64] = lag_k,
            out: &mut [f64] = out,
        ))
    }

    #[inline(always)]
    fn unit_many_portable(&self, inv_rho: f64, n: usize, lag_k: &mut [f64], out: &mut [f64]) {
        let (s, m) = (self.lanes, n.div_ceil(LANES) * LANES);
        let t = &self.table;
        // The leading padding lags: K_t from the BVs' prefixes.
        let p = t.lead;
        for lag in 0..p {
            let row = &self.prefix[lag * s..lag * s + m];
            lag_k[lag * s..lag * s + m].copy_from_slice(row);
        }
        match p {
            0 => out[..m].fill(1.0),
            p => out[..m].copy_from_slice(&self.prefix[(p - 1) * s..(p - 1) * s + m]),
        }
        for lag in p..self.tau {
            let row = t.row(lag);
            let kt = &mut lag_k[lag * s..lag * s + m];
            // Every index is a slot of the table, below the row's length: `get` instead of
            // indexing lets the loop compile to vector gathers (a bounds check that may
            // panic keeps it scalar).
            for (d, &j) in kt.iter_mut().zip(&self.index[lag * s..lag * s + m]) {
                debug_assert!((j as usize) < row.len());
                *d = row.get(j as usize).copied().unwrap_or(f64::NAN);
            }
            for (k, r) in out[..m].iter_mut().zip(kt.iter_mut()) {
                *k = exp_nonpos(-0.5 * *r + (*k - 1.0) * inv_rho);
                *r = *k;
            }
        }
    }
}

impl Inputs {
    /// Unit K_tau as [`Inputs::unit_many`] gives it (bit for bit), without K_t per lag:
    /// over a pair table that holds the observed window and every BV's, read from its
    /// window kernel.
    pub(crate) fn unit_k(&mut self, inv_rho: f64, n: usize, out: &mut [f64]) {
        if self.table.paired.is_some() {
            if self.window_k(n, out) {
                return;
            }
            self.table.ensure_rows();
        }
        self.unit_k_from_rows(inv_rho, n, out);
    }

    /// K_tau of BVs 0..n read from the pair table's window kernel into `out`; false if it
    /// does not hold the observed window or a BV's (`out` then holds nothing of use).
    fn window_k(&self, n: usize, out: &mut [f64]) -> bool {
        dispatch_wide!(["avx512f", "avx2"] Inputs::window_k_portable, (
            this: &Inputs = self,
            n: usize = n,
            out: &mut [f64] = out,
        ) -> bool)
    }

    #[inline(always)]
    fn window_k_portable(&self, n: usize, out: &mut [f64]) -> bool {
        let paired = self.table.paired.as_deref();
        let Some(row) = paired.and_then(|p| p.pairs.window_row(p.window)) else {
            return false;
        };
        let m = n.div_ceil(LANES) * LANES;
        for (k, &w) in out[..m].iter_mut().zip(&self.window[..m]) {
            // `get`: a gather (the ids of windows not held read as NaN).
            *k = row.get(w as usize).copied().unwrap_or(f64::NAN);
        }
        !out[..n].iter().any(|k| k.is_nan())
    }

    fn unit_k_from_rows(&self, inv_rho: f64, n: usize, out: &mut [f64]) {
        dispatch_wide!(["avx512f", "avx2"] Inputs::unit_k_portable, (
            this: &Inputs = self,
            inv_rho: f64 = inv_rho,
            n: usize = n,
            out: &mut [f64] = out,
        ))
    }

    #[inline(always)]
    fn unit_k_portable(&self, inv_rho: f64, n: usize, out: &mut [f64]) {
        let (s, m) = (self.lanes, n.div_ceil(LANES) * LANES);
        let t = &self.table;
        let p = t.lead;
        match p {
            0 => out[..m].fill(1.0),
            p => out[..m].copy_from_slice(&self.prefix[(p - 1) * s..(p - 1) * s + m]),
        }
        for lag in p..self.tau {
            let row = t.row(lag);
            for (k, &j) in out[..m].iter_mut().zip(&self.index[lag * s..lag * s + m]) {
                debug_assert!((j as usize) < row.len());
                let r = row.get(j as usize).copied().unwrap_or(f64::NAN);
                *k = exp_nonpos(-0.5 * r + (*k - 1.0) * inv_rho);
            }
        }
    }
}
