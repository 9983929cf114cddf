//! The workbench in an egui_kittest harness, opened on the bundled sample sessions.

use std::time::{Duration, Instant};

use egui_kittest::Harness;
use tactile_workbench::app::WorkbenchApp;

/// A harness of `width` × `height` at 60 frames per second, returned once both samples
/// have loaded on their worker thread (bounded wait).
pub fn workbench(width: f32, height: f32) -> Harness<'static, WorkbenchApp> {
    workbench_opening(Vec::new(), width, height)
}

/// A harness opened on `files` (sessions or projects) instead of the samples, returned once
/// two sessions have loaded.
pub fn workbench_opening(
    files: Vec<std::path::PathBuf>,
    width: f32,
    height: f32,
) -> Harness<'static, WorkbenchApp> {
    let app = WorkbenchApp::new(&egui::Context::default(), None, files);
    harness_of(app, width, height)
}

/// A harness on `app` at 60 frames per second, returned at once.
pub fn harness_now(app: WorkbenchApp, width: f32, height: f32) -> Harness<'static, WorkbenchApp> {
    Harness::builder()
        .with_size(egui::Vec2::new(width, height))
        .with_step_dt(1.0 / 60.0)
        .build_ui_state(
            |ui, app: &mut WorkbenchApp| {
                app.tick(ui.ctx());
                app.show(ui);
            },
            app,
        )
}

/// Step until no job runs (bounded by `limit`, a guard against hangs), sleeping so the
/// workers get the CPU.
pub fn wait_for_jobs(h: &mut Harness<'static, WorkbenchApp>, limit: Duration) {
    let t = Instant::now();
    while h.state().analyses.busy() && t.elapsed() < limit {
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    h.run_ok();
}

/// A harness on `app`, returned once two sessions have loaded.
pub fn harness_of(app: WorkbenchApp, width: f32, height: f32) -> Harness<'static, WorkbenchApp> {
    let mut h = harness_now(app, width, height);
    let t = Instant::now();
    while (h.state().is_loading() || h.state().sessions.len() < 2)
        && t.elapsed() < Duration::from_secs(30)
    {
        h.step();
        std::thread::sleep(Duration::from_millis(10));
    }
    assert_eq!(
        h.state().sessions.len(),
        2,
        "errors: {:?}",
        h.state().analyses.notes.texts()
    );
    h.run_ok();
    h
}
