//! The native window around the workbench, and the measurements it makes of itself.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::persisted::Persisted;
use super::{STORAGE_KEY, View, WorkbenchApp};

/// A measurement the window makes of itself, then quits.
#[derive(Clone, Copy, Debug)]
pub enum Measure {
    /// The time from the process start to the first frame and to the sessions shown.
    Startup(Instant),
    /// Per-frame UI time (layout and tessellation, not GPU painting) of the grasp-stability
    /// view for `seconds` while a 108-cell grid search runs on the grasp-stability sample.
    Frames { seconds: f64 },
}

struct EframeApp {
    app: WorkbenchApp,
    measure: Option<Measure>,
    first_frame: Option<f64>,
    /// UI times (ms) of the frames drawn while the measured grid search ran.
    frame_ms: Vec<f64>,
    measuring_since: Option<Instant>,
    /// Why the startup measurement failed (what it opened did not load), for `run` to return.
    failed: Arc<Mutex<Option<String>>>,
}

impl EframeApp {
    /// `--measure-frames`: start the grid once the samples are in, time each frame.
    fn measure_frames(&mut self, ui: &egui::Ui, seconds: f64, ms: f64) {
        let ctx = ui.ctx().clone();
        match self.measuring_since {
            None if !self.app.is_loading() && !self.app.sessions.is_empty() => {
                let stability = self
                    .app
                    .sessions
                    .iter()
                    .position(|s| s.session.label_sets.iter().any(|l| l.classes.len() == 2));
                if let Some(i) = stability {
                    self.app.browser.active = i;
                    self.app.view = View::Stability;
                    self.app.rooms.stability.form.grid = true;
                    self.app.start(&ctx, View::Stability);
                    self.measuring_since = Some(Instant::now());
                }
            }
            Some(t0) => {
                let running = self.app.analyses.busy();
                if running {
                    self.frame_ms.push(ms);
                }
                if !running || t0.elapsed().as_secs_f64() > seconds {
                    let mut v = self.frame_ms.clone();
                    v.sort_by(f64::total_cmp);
                    let n = v.len().max(1);
                    let mean = v.iter().sum::<f64>() / n as f64;
                    let p95 = v.get(n * 95 / 100).copied().unwrap_or(0.0);
                    let max = v.last().copied().unwrap_or(0.0);
                    println!(
                        "{} frames during the grid search: UI time mean {mean:.2} ms, p95 {p95:.2} ms, max {max:.2} ms",
                        v.len()
                    );
                    self.app.analyses.jobs.iter().for_each(|j| j.job.cancel());
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                    self.measure = None;
                    return;
                }
            }
            None => {}
        }
        // Keep drawing, as an animation would, so frames are timed continuously.
        ctx.request_repaint();
    }
}

impl eframe::App for EframeApp {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        self.app.tick(ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let t = Instant::now();
        self.app.show(ui);
        let frame_ms = t.elapsed().as_secs_f64() * 1e3;
        match self.measure {
            Some(Measure::Startup(t0)) => {
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                let first = *self.first_frame.get_or_insert(ms);
                match self.app.startup_outcome() {
                    // Keep drawing: a failed load may bring no event to wake the window.
                    None => ui.ctx().request_repaint(),
                    Some(outcome) => {
                        match outcome {
                            Ok(()) => {
                                println!("first frame: {first:.0} ms; sessions shown: {ms:.0} ms")
                            }
                            Err(e) => {
                                if let Ok(mut failed) = self.failed.lock() {
                                    *failed = Some(e);
                                }
                            }
                        }
                        ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                        // Report once: frames may still be drawn while the window closes.
                        self.measure = None;
                    }
                }
            }
            Some(Measure::Frames { seconds }) => self.measure_frames(ui, seconds, frame_ms),
            None => {}
        }
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if self.measure.is_none() && self.measuring_since.is_none() {
            eframe::set_value(storage, STORAGE_KEY, &self.app.persisted());
        }
    }
}

/// Open the workbench window; with `measure`, measure the window itself, print the result
/// and close.
pub fn run(
    files: Vec<PathBuf>,
    view: Option<View>,
    measure: Option<Measure>,
) -> anyhow::Result<()> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("Tactile Workbench")
            .with_inner_size([1400.0, 900.0])
            .with_drag_and_drop(true),
        ..Default::default()
    };
    let failed = Arc::new(Mutex::new(None));
    let failed_in_app = Arc::clone(&failed);
    eframe::run_native(
        "Tactile Workbench",
        options,
        Box::new(move |cc| {
            // A measurement always starts from the bundled samples.
            let persisted = cc
                .storage
                .filter(|_| measure.is_none())
                .and_then(|s| eframe::get_value::<Persisted>(s, STORAGE_KEY));
            let mut app = WorkbenchApp::new(&cc.egui_ctx, persisted, files);
            if let Some(v) = view {
                app.view = v;
            }
            // A measurement neither reads nor overwrites the results kept between runs.
            if measure.is_none()
                && let Some(dir) = eframe::storage_dir("Tactile Workbench")
            {
                app.keep_results_in(&cc.egui_ctx, dir);
            }
            Ok(Box::new(EframeApp {
                app,
                measure,
                first_frame: None,
                frame_ms: Vec::new(),
                measuring_since: None,
                failed: failed_in_app,
            }))
        }),
    )
    .map_err(|e| anyhow::anyhow!("could not open the window: {e}"))?;
    match failed.lock().ok().and_then(|mut f| f.take()) {
        Some(e) => anyhow::bail!("--measure-startup: nothing to measure, the opening failed:\n{e}"),
        None => Ok(()),
    }
}
