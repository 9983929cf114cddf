//! The Compare view's speed on the real datasets (skipped when they are absent):
//!
//! - frame time of the whole window (UI pass and tessellation, as a real window spends on
//!   the CPU per frame) with every iCub grasp overlaid, and with every BTS3 grasp as a
//!   point, while the pointer sweeps the plots: p50, p95 and the worst of 300 frames, and
//!   their mean with the share of it on a CPU (the rest is waiting for one on a busy
//!   machine);
//! - the groups' statistics over BTS3 × 100 (127,600 grasps), headless, as the view's
//!   worker computes them: extraction, alignment and the distributions' figure, and the
//!   bands alone; median and worst of 5 runs.
//!
//! Run: `cargo bench --profile dev --bench compare` (the dev profile is optimised; a
//! release build of the window takes far longer to compile).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use egui::{Pos2, Rect, Vec2};
use tactile_workbench::app::{View, WorkbenchApp};
use tactile_workbench::compare::{self, Event, Groups, Request, SensorStat, Signal, Spread, stats};
use tactile_workbench::session::{self, Session};

const FRAMES: usize = 300;
const SIZE: Vec2 = Vec2::new(1400.0, 900.0);

fn datasets() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/datasets"))
}

fn percentile(sorted: &[Duration], p: f64) -> Duration {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn ms(d: Duration) -> String {
    format!("{:.2} ms", d.as_secs_f64() * 1e3)
}

/// This thread's time on a CPU so far (Linux: `/proc/thread-self/schedstat`), to tell the
/// frame's own work from time the thread waited for a CPU on a busy machine.
fn on_cpu() -> Option<Duration> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    Some(Duration::from_nanos(
        s.split_whitespace().next()?.parse().ok()?,
    ))
}

/// One frame of the whole window: the UI pass and its tessellation; its wall time and its
/// time on a CPU.
fn frame(
    ctx: &egui::Context,
    app: &mut WorkbenchApp,
    t: f64,
    pointer: Option<Pos2>,
) -> (Duration, Option<Duration>) {
    let mut input = egui::RawInput {
        screen_rect: Some(Rect::from_min_size(Pos2::ZERO, SIZE)),
        time: Some(t),
        ..Default::default()
    };
    if let Some(p) = pointer {
        input.events.push(egui::Event::PointerMoved(p));
    }
    let cpu0 = on_cpu();
    let t0 = Instant::now();
    let out = ctx.run_ui(input, |ui| {
        app.tick(ui.ctx());
        app.show(ui);
    });
    let mut out = out;
    let _ = ctx.tessellate(std::mem::take(&mut out.shapes), out.pixels_per_point);
    let spent = t0.elapsed();
    let cpu = on_cpu().zip(cpu0).map(|(b, a)| b.saturating_sub(a));
    // No GPU here: the new textures (font atlas) are dropped.
    out.textures_delta.clear();
    (spent, cpu)
}

/// The window opened on `file`, in the Compare view once its comparison is computed; then
/// the frame times of 300 frames as the pointer sweeps the central area.
fn frame_times(what: &str, file: PathBuf) {
    let ctx = egui::Context::default();
    let mut app = WorkbenchApp::new(&ctx, None, vec![file]);
    let mut t = 0.0;
    let start = Instant::now();
    while (app.is_loading() || app.sessions.is_empty()) && start.elapsed().as_secs() < 120 {
        frame(&ctx, &mut app, t, None);
        t += 1.0 / 60.0;
        std::thread::sleep(Duration::from_millis(10));
    }
    let Some(active) =
        (app.sessions.iter()).position(|s| !s.session.meta.name.contains("Simulated"))
    else {
        println!("{what}: the session did not load");
        return;
    };
    app.browser.active = active;
    app.view = View::Compare;
    while (app.rooms.compare.computing() || app.rooms.compare.shown.is_none())
        && start.elapsed().as_secs() < 120
    {
        frame(&ctx, &mut app, t, None);
        t += 1.0 / 60.0;
        std::thread::sleep(Duration::from_millis(10));
    }
    // Warm up (fonts, galleys), then measure with the pointer sweeping the tiles.
    for _ in 0..20 {
        frame(&ctx, &mut app, t, None);
        t += 1.0 / 60.0;
    }
    let measured: Vec<(Duration, Option<Duration>)> = (0..FRAMES)
        .map(|k| {
            let u = k as f32 / FRAMES as f32;
            let row = (k / 50) as f32 / (FRAMES / 50) as f32;
            let p = Pos2::new(330.0 + 800.0 * ((u * 6.0) % 1.0), 120.0 + 740.0 * row);
            t += 1.0 / 60.0;
            frame(&ctx, &mut app, t, Some(p))
        })
        .collect();
    let mut times: Vec<Duration> = measured.iter().map(|m| m.0).collect();
    times.sort_unstable();
    // The scheduler updates a thread's CPU time at its ticks: a frame's own reading is
    // coarse, their sum over the run is not.
    let cpu: Option<Duration> = measured.iter().map(|m| m.1).sum();
    let shown = app.rooms.compare.shown.as_ref().expect("computed");
    let points: usize = match &shown.overlay.kind {
        tactile_workbench::figures::FigureKind::Chart(c) => {
            c.series.iter().map(|s| s.y.len()).sum()
        }
        _ => 0,
    };
    println!(
        "{what}: {} grasps, overlay of {points} points; frame time over {FRAMES} frames at {}×{}: \
         p50 {}, p95 {}, worst {}; mean {} of which on a CPU {}",
        app.sessions[active].session.grasps.len(),
        SIZE.x,
        SIZE.y,
        ms(percentile(&times, 0.5)),
        ms(percentile(&times, 0.95)),
        ms(*times.last().unwrap()),
        ms(times.iter().sum::<Duration>() / FRAMES as u32),
        cpu.map_or("n/a".into(), |d| ms(d / FRAMES as u32)),
    );
}

/// BTS3's grasps `copies` times over (a session of 127,600 grasps for 100).
fn replicated(s: &Session, copies: usize) -> Session {
    let mut big = s.clone();
    big.grasps = (0..copies).flat_map(|_| s.grasps.iter().cloned()).collect();
    big
}

fn timed<T>(runs: usize, mut f: impl FnMut() -> T) -> (Duration, Duration) {
    let mut times: Vec<Duration> = (0..runs)
        .map(|_| {
            let t0 = Instant::now();
            std::hint::black_box(f());
            t0.elapsed()
        })
        .collect();
    times.sort_unstable();
    (times[times.len() / 2], *times.last().unwrap())
}

fn group_statistics(bts3: &Session) {
    let big = replicated(bts3, 100);
    let groups = Groups::by_label_set(&big, 0);
    let all: Vec<usize> = (0..big.grasps.len()).collect();
    for signal in [
        Signal::Taxel {
            sensor: 1,
            taxel: 6,
        },
        Signal::Sensor {
            sensor: 0,
            stat: SensorStat::Total,
        },
    ] {
        let request = Request {
            signal,
            event: Event::ContactOnset,
            spread: Spread::MeanSd,
            overlaid: Vec::new(),
            groups: groups.clone(),
            seed: 1,
        };
        let (median, worst) = timed(5, || compare::group_figure(&big, &[], &request));
        println!(
            "groups of {} over {} grasps (BTS3 × 100), distributions and their figure: \
             median {}, worst {} of 5",
            signal.name(&big, &[]).0,
            big.grasps.len(),
            ms(median),
            ms(worst)
        );
    }
    let traces = stats::traces(&big, &[], Signal::HandTotal, Event::ContactOnset, &all);
    for spread in Spread::ALL {
        let (median, worst) = timed(5, || stats::bands(&traces, &groups, spread, 1.0));
        println!(
            "bands ({}) of {} traces: median {}, worst {} of 5",
            spread.text(),
            traces.len(),
            ms(median),
            ms(worst)
        );
    }
}

fn main() {
    let root = datasets();
    let (icub, bts3) = (
        root.join("icub-grasp"),
        root.join("bts3/biotac-palmdown-grasps.csv"),
    );
    if !icub.exists() || !bts3.exists() {
        println!("SKIPPED: the real datasets are not in {}", root.display());
        return;
    }
    println!(
        "threads: {} (rayon), {} logical CPUs",
        rayon::current_num_threads(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    let bts3_session = session::open(&bts3).expect("BTS3 opens");
    group_statistics(&bts3_session);
    frame_times("iCub", icub);
    frame_times("BTS3", bts3);
}
