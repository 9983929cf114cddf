//! The sequences of a session: each grasp's rows of the chosen families, checked against
//! the session, then min-max normalised.

use ndarray::{Array2, ArrayViewMut1};

use super::{Family, FeatureSequences, SequenceError, SequenceParams, SequenceRange};
use crate::features::FingerStats;
use crate::features::codes::FrameCodes;
use crate::rng::Rng;
use crate::session::{Frame, Grasp, Session};

pub fn feature_sequences(
    session: &Session,
    params: &SequenceParams,
) -> Result<FeatureSequences, SequenceError> {
    feature_sequences_in(session, params, SequenceRange::Session, None)
}

/// The sequences normalised to the min-max range `range` gives (values of a new session
/// may fall outside [0, 1] on a range it did not set); `codes` are coded on `codes`'
/// dictionaries (a model's), else on dictionaries learned on the session.
pub fn feature_sequences_in(
    session: &Session,
    params: &SequenceParams,
    range: SequenceRange,
    codes: Option<&FrameCodes>,
) -> Result<FeatureSequences, SequenceError> {
    params.validate()?;
    let used = params.features.resolve(session);
    let families = used.families();
    let set = used.name();
    check_session(session, &families, &set)?;
    let taxel_counts: Vec<usize> = session
        .sensors
        .iter()
        .map(|s| s.layout.taxel_count())
        .collect();
    let mut names = column_names(session, &families, &taxel_counts);
    let codes = if families.contains(&Family::Codes) {
        let book = codes_book(session, params, codes, &taxel_counts, &set)?;
        for (s, width) in session.sensors.iter().zip(book.widths()) {
            names.extend((0..width).map(|k| format!("{}/codes/{k}", s.name)));
        }
        Some(book)
    } else {
        None
    };
    let codes_from = names.len() - codes.as_ref().map_or(0, |c| c.widths().iter().sum());
    let has = |f: Family| families.contains(&f);
    let columns = Columns {
        session,
        tactile: families.iter().any(|f| f.uses_taxels()),
        // Raw, change and codes read every taxel, so every frame must have the layout's count.
        per_taxel: has(Family::Raw) || has(Family::Change) || has(Family::Codes),
        families,
        set,
        taxel_counts,
        sd: params.taxel_noise_variance.sqrt(),
        seed: params.seed,
        codes,
        codes_from,
        dim: names.len(),
    };
    let mut sequences = session
        .grasps
        .iter()
        .enumerate()
        .map(|(g, grasp)| columns.grasp(g, grasp))
        .collect::<Result<Vec<_>, _>>()?;
    let (min, max) = min_max(range, &sequences, columns.dim)?;
    normalise(&mut sequences, &min, &max);
    Ok(FeatureSequences {
        names,
        families: used,
        sequences,
        min,
        max,
        codes: columns.codes,
    })
}

/// The session has what the families read: encoders, tactile sensors, and for `change`
/// a grasp of more than one frame.
fn check_session(session: &Session, families: &[Family], set: &str) -> Result<(), SequenceError> {
    let has = |f: Family| families.contains(&f);
    let lacks = |reason: &str| {
        Err(SequenceError::Session {
            set: set.to_string(),
            reason: reason.into(),
        })
    };
    if has(Family::Encoders) && session.encoders.is_empty() {
        return lacks("it has no joint encoders");
    }
    if families.iter().any(|f| f.uses_taxels()) && session.sensors.is_empty() {
        return lacks("it has no tactile sensors");
    }
    if has(Family::Change) && session.grasps.iter().all(|g| g.frames.len() <= 1) {
        return lacks("every grasp has one frame, so every change since the first is 0");
    }
    Ok(())
}

/// The names of the columns of every family but `codes` (whose widths its dictionaries
/// give), in column order.
fn column_names(session: &Session, families: &[Family], taxel_counts: &[usize]) -> Vec<String> {
    let mut names = Vec::new();
    for &f in families {
        match f {
            Family::Encoders => {
                names.extend(session.encoders.iter().map(|e| format!("encoder/{e}")));
            }
            Family::Moments => {
                for s in &session.sensors {
                    for stat in FingerStats::NAMES {
                        names.push(format!("{}/{stat}", s.name));
                    }
                }
            }
            Family::Raw | Family::Change => {
                for (s, &n) in session.sensors.iter().zip(taxel_counts) {
                    names.extend((0..n).map(|i| format!("{}/{}/{i}", s.name, f.name())));
                }
            }
            Family::Codes => {}
        }
    }
    names
}

/// The codes' dictionaries: the model's (`given`, checked to fit the session's sensors),
/// else learned on every frame of the session.
fn codes_book(
    session: &Session,
    params: &SequenceParams,
    given: Option<&FrameCodes>,
    taxel_counts: &[usize],
    set: &str,
) -> Result<FrameCodes, SequenceError> {
    match given {
        Some(book) => {
            if book.widths().len() != taxel_counts.len()
                || book
                    .sensors
                    .iter()
                    .zip(taxel_counts)
                    .any(|(c, &n)| c.mean.len() != n)
            {
                return Err(SequenceError::Session {
                    set: set.to_string(),
                    reason: "its sensors' taxels are not those of the codes' dictionaries".into(),
                });
            }
            Ok(book.clone())
        }
        None => {
            learn_codes(session, params, taxel_counts).map_err(|source| SequenceError::LearnCodes {
                set: set.to_string(),
                source,
            })
        }
    }
}

/// What the rows of every grasp hold on a session: the families in column order and what
/// reading them needs.
struct Columns<'s> {
    session: &'s Session,
    families: Vec<Family>,
    /// The feature set's name, for errors.
    set: String,
    taxel_counts: Vec<usize>,
    /// Whether a family reads the taxels.
    tactile: bool,
    /// Whether a family reads each taxel (raw, change, codes).
    per_taxel: bool,
    /// Standard deviation of the noise on each raw reading, and its seed.
    sd: f64,
    seed: u64,
    codes: Option<FrameCodes>,
    /// The first column of the codes.
    codes_from: usize,
    dim: usize,
}

impl Columns<'_> {
    /// Grasp `g`'s T × D rows, not yet normalised (noise from stream `g` of the seed).
    fn grasp(&self, g: usize, grasp: &Grasp) -> Result<Array2<f64>, SequenceError> {
        let mut rng = Rng::stream(self.seed, g as u64);
        let mut m = Array2::zeros((grasp.frames.len(), self.dim));
        // Pressures of the grasp's first frame (with its noise), for `change`.
        let mut first: Vec<Vec<f64>> = Vec::new();
        // Every frame's pressures per sensor, for `codes` (coded once per grasp).
        let mut by_sensor: Vec<Vec<f64>> = vec![Vec::new(); self.session.sensors.len()];
        for (t, frame) in grasp.frames.iter().enumerate() {
            let pressures = self.pressures(g, t, frame, &mut rng)?;
            if t == 0 {
                first = pressures.clone();
            }
            if self.codes.is_some() {
                for (all, p) in by_sensor.iter_mut().zip(&pressures) {
                    all.extend_from_slice(p);
                }
            }
            self.fill_row(m.row_mut(t), frame, &pressures, &first);
        }
        if let Some(book) = &self.codes {
            self.put_codes(book, g, by_sensor, &mut m)?;
        }
        Ok(m)
    }

    /// Frame `t` of grasp `g` checked against the session, and its pressures per sensor
    /// (none without a tactile family), each raw reading with its noise.
    fn pressures(
        &self,
        g: usize,
        t: usize,
        frame: &Frame,
        rng: &mut Rng,
    ) -> Result<Vec<Vec<f64>>, SequenceError> {
        let session = self.session;
        let bad_frame = |reason: String| SequenceError::Session {
            set: self.set.clone(),
            reason: format!("grasp {g} frame {t} {reason}"),
        };
        let n_enc = session.encoders.len();
        if self.families.contains(&Family::Encoders) && frame.encoders.len() != n_enc {
            return Err(bad_frame(format!(
                "has {} encoders, the session names {n_enc}",
                frame.encoders.len()
            )));
        }
        let mut pressures: Vec<Vec<f64>> = Vec::new();
        if !self.tactile {
            return Ok(pressures);
        }
        if frame.taxels.len() != session.sensors.len() {
            return Err(bad_frame(
                "does not have one taxel vector per sensor".into(),
            ));
        }
        for (s, raw) in frame.taxels.iter().enumerate() {
            if self.per_taxel && raw.len() != self.taxel_counts[s] {
                return Err(bad_frame(format!(
                    "has {} taxels on sensor {}, its layout {}",
                    raw.len(),
                    session.sensors[s].name,
                    self.taxel_counts[s]
                )));
            }
            pressures.push(
                raw.iter()
                    .enumerate()
                    .map(|(i, &v)| {
                        let noisy = if self.sd > 0.0 {
                            v + self.sd * rng.normal()
                        } else {
                            v
                        };
                        session.pressure(s, i, noisy)
                    })
                    .collect(),
            );
        }
        Ok(pressures)
    }

    /// A frame's row of every family but `codes`, in column order; `first` holds the
    /// pressures of the grasp's first frame.
    fn fill_row(
        &self,
        mut row: ArrayViewMut1<f64>,
        frame: &Frame,
        pressures: &[Vec<f64>],
        first: &[Vec<f64>],
    ) {
        let mut c = 0;
        let mut put = |v: f64| {
            row[c] = v;
            c += 1;
        };
        for &f in &self.families {
            match f {
                Family::Encoders => frame.encoders.iter().for_each(|&e| put(e)),
                Family::Moments => {
                    for p in pressures {
                        FingerStats::of(p).to_array().into_iter().for_each(&mut put);
                    }
                }
                Family::Raw => pressures.iter().flatten().for_each(|&p| put(p)),
                Family::Change => pressures
                    .iter()
                    .flatten()
                    .zip(first.iter().flatten())
                    .for_each(|(&p, &p0)| put(p - p0)),
                Family::Codes => {}
            }
        }
    }

    /// Grasp `g`'s frames coded sensor by sensor on `book`, into the codes' columns of `m`.
    fn put_codes(
        &self,
        book: &FrameCodes,
        g: usize,
        by_sensor: Vec<Vec<f64>>,
        m: &mut Array2<f64>,
    ) -> Result<(), SequenceError> {
        let mut col = self.codes_from;
        for (s, all) in by_sensor.into_iter().enumerate() {
            let frames = Array2::from_shape_vec((m.nrows(), self.taxel_counts[s]), all).map_err(
                |source| SequenceError::Shape {
                    set: self.set.clone(),
                    grasp: g,
                    source,
                },
            )?;
            let coded = book
                .encode(s, frames.view())
                .map_err(|source| SequenceError::Codes {
                    set: self.set.clone(),
                    grasp: g,
                    source,
                })?;
            m.slice_mut(ndarray::s![.., col..col + coded.ncols()])
                .assign(&coded);
            col += coded.ncols();
        }
        Ok(())
    }
}

/// Each feature's minimum and maximum as `range` says, over `dim` features.
fn min_max(
    range: SequenceRange,
    sequences: &[Array2<f64>],
    dim: usize,
) -> Result<(Vec<f64>, Vec<f64>), SequenceError> {
    match range {
        SequenceRange::Session => Ok(range_of(sequences, dim)),
        SequenceRange::Grasps(r) => {
            let Some(part) = sequences.get(r.clone()).filter(|p| !p.is_empty()) else {
                return Err(SequenceError::Parameter {
                    name: "range",
                    reason: format!(
                        "grasps {}..{} of a session of {}",
                        r.start,
                        r.end,
                        sequences.len()
                    ),
                });
            };
            Ok(range_of(part, dim))
        }
        SequenceRange::Given { min, max } => {
            if min.len() != dim || max.len() != dim {
                return Err(SequenceError::Parameter {
                    name: "range",
                    reason: format!(
                        "{} minima and {} maxima for {dim} features",
                        min.len(),
                        max.len()
                    ),
                });
            }
            Ok((min.to_vec(), max.to_vec()))
        }
    }
}

/// Every value mapped to [0, 1] on its feature's range.
fn normalise(sequences: &mut [Array2<f64>], min: &[f64], max: &[f64]) {
    for m in sequences {
        for mut row in m.rows_mut() {
            for (j, v) in row.iter_mut().enumerate() {
                let range = max[j] - min[j];
                // A constant feature carries nothing: it becomes 0 rather than 0/0.
                *v = if range > 0.0 {
                    (*v - min[j]) / range
                } else {
                    0.0
                };
            }
        }
    }
}

/// One dictionary per sensor, learned on every frame's pressures (with the session's noise).
fn learn_codes(
    session: &Session,
    params: &SequenceParams,
    taxel_counts: &[usize],
) -> Result<FrameCodes, crate::sparse::SparseError> {
    let sd = params.taxel_noise_variance.sqrt();
    let mut frames: Vec<Vec<f64>> = vec![Vec::new(); taxel_counts.len()];
    let mut rows = 0;
    for (g, grasp) in session.grasps.iter().enumerate() {
        let mut rng = Rng::stream(params.seed, g as u64);
        for (t, frame) in grasp.frames.iter().enumerate() {
            rows += 1;
            let counts: Vec<usize> = frame.taxels.iter().map(Vec::len).collect();
            if counts != taxel_counts {
                return Err(crate::sparse::SparseError::Data(format!(
                    "grasp {g} frame {t} has {counts:?} taxels per sensor, the layouts \
                     {taxel_counts:?}"
                )));
            }
            for (s, raw) in frame.taxels.iter().enumerate() {
                frames[s].extend(raw.iter().enumerate().map(|(i, &v)| {
                    let noisy = if sd > 0.0 { v + sd * rng.normal() } else { v };
                    session.pressure(s, i, noisy)
                }));
            }
        }
    }
    let frames: Vec<Array2<f64>> = frames
        .into_iter()
        .zip(taxel_counts)
        .map(|(v, &n)| {
            Array2::from_shape_vec((rows, n), v).map_err(crate::sparse::SparseError::from)
        })
        .collect::<Result<_, _>>()?;
    FrameCodes::learn(&frames, params.seed)
}

/// Each feature's least and greatest value over every frame of `sequences`.
fn range_of(sequences: &[Array2<f64>], dim: usize) -> (Vec<f64>, Vec<f64>) {
    let mut min = vec![f64::INFINITY; dim];
    let mut max = vec![f64::NEG_INFINITY; dim];
    for m in sequences {
        for row in m.rows() {
            for (j, &v) in row.iter().enumerate() {
                min[j] = min[j].min(v);
                max[j] = max[j].max(v);
            }
        }
    }
    (min, max)
}
