//! The `render-figure` path on arbitrary bytes: JSON → `Figure`; a figure that validates
//! must render (SVG, PNG) and export to CSV without panicking, or be refused with a message.
#![no_main]

use libfuzzer_sys::fuzz_target;
use tactile_workbench::figures::{
    Figure, FigureError, RenderOptions, render_png, render_svg, to_csv,
};

/// Sizes the CLI accepts: the default, the smallest at the lowest DPI, and a small image
/// at the highest DPI (text larger than the plot).
const OPTIONS: [RenderOptions; 3] = [
    RenderOptions {
        width: 960,
        height: 640,
        dpi: 96.0,
    },
    RenderOptions {
        width: 64,
        height: 64,
        dpi: 24.0,
    },
    RenderOptions {
        width: 200,
        height: 120,
        dpi: 1200.0,
    },
];

fuzz_target!(|data: &[u8]| {
    // `render-figure` reads the file with `read_to_string`: invalid UTF-8 stops there.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(fig) = serde_json::from_str::<Figure>(text) else {
        return;
    };
    let valid = fig.validate().is_ok();
    let opts = &OPTIONS[data.len() % OPTIONS.len()];
    check_render("SVG", valid, render_svg(&fig, opts).map(drop));
    // PNG rasterises the whole image: only at the smallest size, to keep the runs fast.
    let small = RenderOptions {
        width: 64,
        height: 64,
        dpi: opts.dpi,
    };
    check_render("PNG", valid, render_png(&fig, &small).map(drop));
    let csv = to_csv(&fig);
    assert_eq!(csv.is_ok(), valid, "CSV: {:?}", csv.err());
});

/// An invalid figure is refused as invalid; a valid one draws, or is refused because the
/// image is too small for it (an options error the CLI reports), never fails to draw.
fn check_render(format: &str, valid: bool, result: Result<(), FigureError>) {
    match result {
        Ok(()) => assert!(valid, "{format}: an invalid figure was drawn"),
        Err(FigureError::Invalid(m)) => assert!(!valid, "{format}: valid figure refused: {m}"),
        Err(FigureError::Options(m)) => assert!(valid, "{format}: options error first: {m}"),
        Err(e) => panic!("{format}: {e}"),
    }
}
