//! Structural checks of a session: every count agrees with the sensors, every value is
//! finite, every index is in range. The native reader and every importer run these, so a
//! session in memory is always consistent and the analyses never index out of bounds.

use std::path::Path;

use super::{Frame, Grasp, Layout, Sensor, Session, SessionError, ValueTransform};

/// Largest grid area accepted: far above any tactile sensor (the BioTac SP's grid has 72
/// cells), small enough that drawing the grid's image is cheap.
pub const MAX_GRID_CELLS: usize = 65_536;

/// The most taxels one sensor may have, whatever its layout (a full grid's bound).
pub const MAX_TAXELS: usize = MAX_GRID_CELLS;

/// The most sensors a session or a spec may declare: a whole hand of tactile skin patches
/// has tens to hundreds.
pub const MAX_SENSORS: usize = 1_024;

/// Check `session`; errors name `path` and the field.
pub fn validate(session: &Session, path: &Path) -> Result<(), SessionError> {
    let err = |field: String, msg: String| SessionError::field(path, field, msg);
    if session.sensors.is_empty() {
        return Err(err("sensors".into(), "the session has no sensors".into()));
    }
    if session.sensors.len() > MAX_SENSORS {
        return Err(err(
            "sensors".into(),
            format!(
                "{} sensors, more than the {MAX_SENSORS} a session may have",
                session.sensors.len()
            ),
        ));
    }
    for (s, sensor) in session.sensors.iter().enumerate() {
        check_sensor(s, sensor, path)?;
    }
    for (l, set) in session.label_sets.iter().enumerate() {
        if set.classes.is_empty() {
            return Err(err(
                format!("label_sets[{l}]"),
                format!("label set `{}` has no classes", set.name),
            ));
        }
    }
    if session.grasps.is_empty() {
        return Err(err("grasps".into(), "the session has no grasps".into()));
    }
    for (g, grasp) in session.grasps.iter().enumerate() {
        check_grasp(g, grasp, session, path)?;
    }
    Ok(())
}

/// Sensor `s`: its layout, range and value transform.
fn check_sensor(s: usize, sensor: &Sensor, path: &Path) -> Result<(), SessionError> {
    let err = |field: String, msg: String| SessionError::field(path, field, msg);
    check_layout(s, &sensor.name, &sensor.layout, path)?;
    let n = sensor.layout.taxel_count();
    if let Some([lo, hi]) = sensor.range
        && !(lo.is_finite() && hi.is_finite() && lo <= hi)
    {
        return Err(err(
            format!("sensors[{s}].range"),
            format!("[{lo}, {hi}] is not a range of finite values, low to high"),
        ));
    }
    match &sensor.transform {
        ValueTransform::BaselineMinus { baseline } => {
            if baseline.len() != n {
                return Err(err(
                    format!("sensors[{s}].transform.baseline"),
                    format!("{} baselines for {n} taxels", baseline.len()),
                ));
            }
            if baseline.iter().any(|b| !b.is_finite()) {
                return Err(err(
                    format!("sensors[{s}].transform.baseline"),
                    "baselines must be finite".into(),
                ));
            }
        }
        ValueTransform::Reversed { offset } if !offset.is_finite() => {
            return Err(err(
                format!("sensors[{s}].transform.offset"),
                "the offset must be finite".into(),
            ));
        }
        _ => {}
    }
    Ok(())
}

/// The layout of sensor `s` (named `name`), as a session or an import spec (`path`)
/// declares it: a grid neither empty nor past [`MAX_GRID_CELLS`], at most [`MAX_TAXELS`]
/// taxels and at least one, a sparse grid's cells inside it and each once, points with a
/// positive radius and finite positions.
pub(crate) fn check_layout(
    s: usize,
    name: &str,
    layout: &Layout,
    path: &Path,
) -> Result<(), SessionError> {
    let err = |field: String, msg: String| SessionError::field(path, field, msg);
    let at = |rest: &str| format!("sensors[{s}].layout{rest}");
    // The grid size comes from the file: rows × cols must not overflow before
    // `taxel_count` multiplies them (found by fuzzing, tests/fuzz_regressions.rs), and
    // images of the grid are drawn cell by cell, so its area is bounded too.
    if let Some((rows, cols)) = layout.grid_shape()
        && rows
            .checked_mul(cols)
            .is_none_or(|area| area > MAX_GRID_CELLS)
    {
        return Err(err(at(""), format!("a {rows} × {cols} grid is too large")));
    }
    let n = layout.taxel_count();
    if n == 0 {
        return Err(err(at(""), format!("sensor `{name}` has no taxels")));
    }
    if n > MAX_TAXELS {
        return Err(err(
            at(""),
            format!("{n} taxels, more than the {MAX_TAXELS} a sensor may have"),
        ));
    }
    match layout {
        Layout::Grid { .. } => {}
        Layout::SparseGrid { rows, cols, cells } => {
            // One flag per cell of the grid (bounded above), so repeats are found in one pass.
            let mut taken = vec![false; rows * cols];
            for (i, c) in cells.iter().enumerate() {
                if c[0] >= *rows || c[1] >= *cols {
                    return Err(err(
                        at(&format!(".cells[{i}]")),
                        format!(
                            "cell ({}, {}) is outside the {rows} × {cols} grid",
                            c[0], c[1]
                        ),
                    ));
                }
                if std::mem::replace(&mut taken[c[0] * cols + c[1]], true) {
                    return Err(err(
                        at(&format!(".cells[{i}]")),
                        format!(
                            "cell ({}, {}) is listed twice: two taxels cannot share a cell",
                            c[0], c[1]
                        ),
                    ));
                }
            }
        }
        Layout::Points {
            positions, radius, ..
        } => {
            if !(radius.is_finite() && *radius > 0.0) {
                return Err(err(
                    at(".radius"),
                    format!("taxel radius must be positive, found {radius}"),
                ));
            }
            if positions
                .iter()
                .any(|p| !p.x.is_finite() || !p.y.is_finite())
            {
                return Err(err(
                    at(".positions"),
                    "taxel positions must be finite".into(),
                ));
            }
        }
    }
    Ok(())
}

/// Grasp `g`: a class of each label set, a key frame among its frames, and its frames.
fn check_grasp(
    g: usize,
    grasp: &Grasp,
    session: &Session,
    path: &Path,
) -> Result<(), SessionError> {
    let err = |field: String, msg: String| SessionError::field(path, field, msg);
    let at = |rest: &str| format!("grasps[{g}]{rest}");
    if grasp.labels.len() != session.label_sets.len() {
        return Err(err(
            at(".labels"),
            format!(
                "{} labels for {} label sets",
                grasp.labels.len(),
                session.label_sets.len()
            ),
        ));
    }
    for (l, &c) in grasp.labels.iter().enumerate() {
        let k = session.label_sets[l].classes.len();
        if c >= k {
            return Err(err(
                at(&format!(".labels[{l}]")),
                format!(
                    "class {c} is out of range (label set `{}` has {k})",
                    session.label_sets[l].name
                ),
            ));
        }
    }
    if grasp.frames.is_empty() {
        return Err(err(at(".frames"), "the grasp has no frames".into()));
    }
    if grasp.key_frame >= grasp.frames.len() {
        return Err(err(
            at(".key_frame"),
            format!(
                "key frame {} but the grasp has {} frames",
                grasp.key_frame,
                grasp.frames.len()
            ),
        ));
    }
    let mut last_t = f64::NEG_INFINITY;
    for (f, frame) in grasp.frames.iter().enumerate() {
        let fat = |rest: &str| format!("grasps[{g}].frames[{f}]{rest}");
        if !frame.t.is_finite() || frame.t < last_t {
            return Err(err(
                fat(".t"),
                format!("time {} is not finite or goes backwards", frame.t),
            ));
        }
        last_t = frame.t;
        check_frame_values(frame, session, fat, path)?;
    }
    Ok(())
}

/// A frame's readings (one per taxel of each sensor, finite and in the sensor's range)
/// and encoder values (one per encoder, finite); `fat` names a field of the frame.
fn check_frame_values(
    frame: &Frame,
    session: &Session,
    fat: impl Fn(&str) -> String,
    path: &Path,
) -> Result<(), SessionError> {
    let err = |field: String, msg: String| SessionError::field(path, field, msg);
    if frame.taxels.len() != session.sensors.len() {
        return Err(err(
            fat(".taxels"),
            format!(
                "{} sensor readings for {} sensors",
                frame.taxels.len(),
                session.sensors.len()
            ),
        ));
    }
    for (s, values) in frame.taxels.iter().enumerate() {
        let n = session.sensors[s].layout.taxel_count();
        if values.len() != n {
            return Err(err(
                fat(&format!(".taxels[{s}]")),
                format!("expected {n} values, found {}", values.len()),
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(err(
                fat(&format!(".taxels[{s}][{i}]")),
                "value is not finite".into(),
            ));
        }
        let sensor = &session.sensors[s];
        if let Some(i) = values.iter().position(|&v| !sensor.in_range(v)) {
            return Err(err(
                fat(&format!(".taxels[{s}][{i}]")),
                format!(
                    "reading {} is outside sensor `{}`'s range {}",
                    values[i],
                    sensor.name,
                    sensor.range_text()
                ),
            ));
        }
    }
    let n_enc = session.encoders.len();
    if frame.encoders.len() != n_enc {
        return Err(err(
            fat(".encoders"),
            format!(
                "expected {n_enc} encoder values, found {}",
                frame.encoders.len()
            ),
        ));
    }
    if let Some(i) = frame.encoders.iter().position(|v| !v.is_finite()) {
        return Err(err(
            fat(&format!(".encoders[{i}]")),
            "value is not finite".into(),
        ));
    }
    Ok(())
}
