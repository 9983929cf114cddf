//! Figure export as a user sees it: files that open, with the expected titles, sizes and
//! numbers, and clear errors that leave nothing half-written.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use quick_xml::Reader;
use quick_xml::events::Event;
use tactile_workbench::figures::{
    Axis, AxisTitle, BarGroup, ColorMap, ColorScale, Figure, FigureEntry, FigureError, FigureSet,
    Format, GridImage, Orientation, RenderOptions, Rgb, Series, SeriesStyle, export_all,
    render_png, render_svg, to_csv, write_figure,
};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tw-figures-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn accuracy_chart() -> Figure {
    Figure::chart(
        "Accuracy as trials progress",
        Axis::new("Trials", "count"),
        Axis::new("Accuracy", "%").including(0.0, 100.0),
        vec![
            Series::new("DS learner", vec![1.0, 2.0, 3.0], vec![52.5, 71.25, 88.0])
                .band(vec![50.0, 68.0, 85.0], vec![55.0, 74.0, 91.0]),
            Series::new(
                "GS learner",
                vec![1.0, 2.0, 3.0],
                vec![40.0, f64::NAN, 80.0],
            )
            .style(SeriesStyle::LineMarkers),
        ],
    )
    .ref_line(Orientation::Vertical, 2.5, "threshold")
}

fn usage_bars() -> Figure {
    Figure::bars(
        "Basis usage per label",
        AxisTitle::new("Basis", ""),
        Axis::new("Usage", "patches"),
        (1..=4).map(|i| i.to_string()).collect(),
        vec![
            BarGroup::new("success", vec![12.0, 7.0, 0.0, 31.0]),
            BarGroup::new("failure", vec![3.0, 9.5, 4.0, 1.0]).errors(vec![1.0, 0.5, 0.5, 0.25]),
        ],
    )
}

fn differential_heatmap(values: Vec<Vec<f64>>) -> Figure {
    let cols = values[0].len();
    Figure::heatmap(
        "Coefficient differential",
        AxisTitle::new("gamma", ""),
        AxisTitle::new("beta", ""),
        (0..cols).map(|c| format!("g{c}")).collect(),
        (0..values.len()).map(|r| format!("b{r}")).collect(),
        values,
        ColorScale::diverging("Differential", "a.u."),
    )
}

fn basis_grid() -> Figure {
    let images = (0..6)
        .map(|k| GridImage {
            caption: format!("basis {k}"),
            values: (0..7)
                .map(|r| (0..4).map(|c| (r * 4 + c + k) as f64 / 30.0).collect())
                .collect(),
        })
        .collect();
    Figure::image_grid(
        "Dictionary bases",
        images,
        ColorScale::viridis("Basis weight", ""),
    )
}

/// Parse the whole document; return every text node and the `fill` of every `<rect>`.
fn parse_svg(svg: &str) -> (Vec<String>, Vec<String>) {
    let mut reader = Reader::from_str(svg);
    let mut texts = Vec::new();
    let mut fills = Vec::new();
    let mut depth = 0i32;
    // Text arrives in pieces split at entity references (`&gt;`).
    let mut text = String::new();
    let mut flush = |text: &mut String| {
        if !text.trim().is_empty() {
            texts.push(text.trim().to_string());
        }
        text.clear();
    };
    loop {
        match reader.read_event() {
            Ok(Event::Eof) => break,
            Ok(Event::Start(_)) => {
                flush(&mut text);
                depth += 1;
            }
            Ok(Event::End(_)) => {
                flush(&mut text);
                depth -= 1;
            }
            Ok(Event::GeneralRef(r)) => text.push(match r.decode().unwrap().as_ref() {
                "lt" => '<',
                "gt" => '>',
                "amp" => '&',
                "quot" => '"',
                "apos" => '\'',
                other => panic!("unexpected entity &{other};"),
            }),
            Ok(Event::Empty(e)) if e.name().as_ref() == b"rect" => {
                let fill = e
                    .try_get_attribute("fill")
                    .unwrap()
                    .map(|a| String::from_utf8(a.value.to_vec()).unwrap())
                    .unwrap_or_default();
                fills.push(fill);
            }
            Ok(Event::Text(t)) => text.push_str(&t.decode().unwrap()),
            Ok(_) => {}
            Err(e) => panic!(
                "SVG is not well-formed XML at {}: {e}",
                reader.buffer_position()
            ),
        }
    }
    assert_eq!(depth, 0, "unbalanced elements");
    (texts, fills)
}

#[test]
fn chart_svg_is_xml_with_titles_series_and_missing_note() {
    let svg = render_svg(&accuracy_chart(), &RenderOptions::default()).unwrap();
    let (texts, _) = parse_svg(&svg);
    for expected in [
        "Accuracy as trials progress",
        "Trials (count)",
        "Accuracy (%)",
        "DS learner",
        "GS learner (1 missing)",
        "threshold",
    ] {
        assert!(
            texts.iter().any(|t| t == expected),
            "no text {expected:?} in {texts:?}"
        );
    }
}

#[test]
fn heatmap_svg_has_a_colour_bar() {
    let fig = differential_heatmap(vec![vec![-2.0, 0.5], vec![1.0, 0.25]]);
    let svg = render_svg(&fig, &RenderOptions::default()).unwrap();
    let (texts, fills) = parse_svg(&svg);
    assert!(
        texts.iter().any(|t| t == "Differential (a.u.)"),
        "colour bar title: {texts:?}"
    );
    assert!(texts.iter().any(|t| t == "gamma") && texts.iter().any(|t| t == "beta"));
    // A gradient of many colours, with tick labels at the symmetric limits ±2.
    let distinct: std::collections::HashSet<&String> = fills.iter().collect();
    assert!(distinct.len() > 100, "gradient strips: {}", distinct.len());
    assert!(
        texts.iter().any(|t| t == "-2") && texts.iter().any(|t| t == "2"),
        "{texts:?}"
    );
}

#[test]
fn diverging_heatmap_puts_zero_at_the_neutral_colour() {
    let fig = differential_heatmap(vec![vec![-2.0, 0.0, 1.0]]);
    let svg = render_svg(&fig, &RenderOptions::default()).unwrap();
    let (_, fills) = parse_svg(&svg);
    // fills[0] is the background; the cells follow in row-major order.
    assert_eq!(
        fills[1], "#053061",
        "-2 is the low end of the symmetric limits"
    );
    assert_eq!(fills[2], "#F7F7F7", "0 is the neutral centre colour");
    assert_ne!(
        fills[3], "#67001F",
        "1 is half-way to the red end, not at it"
    );
}

#[test]
fn grid_search_map_marks_the_recommended_model() {
    let fig = Figure::heatmap(
        "Grid search",
        AxisTitle::new("gamma", ""),
        AxisTitle::new("beta", ""),
        vec!["0.1".into(), "0.4".into()],
        vec!["0.2".into(), "0.8".into()],
        vec![vec![0.71, 0.8], vec![0.65, 0.775]],
        ColorScale::viridis("Weighted success rate", ""),
    )
    .annotated()
    .mark(0, 1);
    let svg = render_svg(&fig, &RenderOptions::default()).unwrap();
    let (texts, _) = parse_svg(&svg);
    for value in ["0.710", "0.800", "0.650", "0.775"] {
        assert!(
            texts.iter().any(|t| t == value),
            "cell value {value}: {texts:?}"
        );
    }
    assert_eq!(
        svg.matches("stroke=\"#000000\"").count(),
        1,
        "one outlined cell"
    );
    let out_of_range = fig.clone().mark(2, 0);
    assert!(matches!(
        render_svg(&out_of_range, &RenderOptions::default()),
        Err(FigureError::Invalid(_))
    ));
}

#[test]
fn differential_bars_are_coloured_by_sign() {
    let fig = Figure::bars(
        "Usage differential",
        AxisTitle::new("Basis", ""),
        Axis::new("Success − failure", "patches"),
        vec!["1".into(), "2".into(), "3".into()],
        vec![BarGroup::new("differential", vec![4.0, -3.0, f64::NAN])],
    )
    .sign_colored();
    let svg = render_svg(&fig, &RenderOptions::default()).unwrap();
    let (texts, fills) = parse_svg(&svg);
    assert!(
        texts.iter().any(|t| t == "differential > 0 (1 missing)"),
        "{texts:?}"
    );
    assert!(texts.iter().any(|t| t == "differential < 0"));
    // fills: background, then the two bars (the missing one is not drawn).
    let hex = |c: Rgb| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
    let (red, blue) = (ColorMap::Diverging.at(0.85), ColorMap::Diverging.at(0.15));
    assert!(red.0 > red.2 && blue.2 > blue.0);
    assert_eq!(fills[1], hex(red), "positive bar in the red half");
    assert_eq!(fills[2], hex(blue), "negative bar in the blue half");
}

fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    (be(16), be(20))
}

#[test]
fn png_decodes_at_the_asked_size_and_dpi() {
    for fig in [accuracy_chart(), usage_bars(), basis_grid()] {
        let opts = RenderOptions {
            width: 1200,
            height: 800,
            dpi: 192.0,
        };
        let bytes = render_png(&fig, &opts).unwrap();
        assert_eq!(png_size(&bytes), (1200, 800));
        let mut reader = png::Decoder::new(std::io::Cursor::new(&bytes))
            .read_info()
            .unwrap();
        let dims = reader.info().pixel_dims.expect("pHYs chunk");
        assert_eq!(dims.xppu, (192.0f64 / 0.0254).round() as u32);
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let frame = reader.next_frame(&mut pixels).unwrap();
        assert_eq!((frame.width, frame.height), (1200, 800));
        let inked = pixels
            .chunks(3)
            .filter(|p| p.iter().any(|&c| c < 200))
            .count();
        assert!(
            inked > 5_000,
            "{}: the figure is drawn ({inked} dark pixels)",
            fig.title
        );
    }
}

#[test]
fn csv_holds_the_numbers() {
    let csv = to_csv(&usage_bars()).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "Basis,success [Usage (patches)],failure [Usage (patches)],failure error"
    );
    assert_eq!(lines[2], "2,7,9.5,0.5");
    assert_eq!(lines.len(), 5);

    let csv = to_csv(&accuracy_chart()).unwrap();
    assert!(csv.starts_with("series,Trials (count),Accuracy (%),lower,upper\n"));
    assert!(csv.contains("DS learner,2,71.25,68,74\n"));
    assert!(csv.contains("GS learner,2,NaN,,\n"));

    let csv = to_csv(&differential_heatmap(vec![vec![-2.0, f64::NAN]])).unwrap();
    assert_eq!(
        csv,
        "beta \\ gamma [Differential (a.u.)],g0,g1\nb0,-2,NaN\n"
    );

    let csv = to_csv(&basis_grid()).unwrap();
    assert_eq!(csv.lines().count(), 1 + 6 * 28);
    assert!(
        csv.ends_with("\n5,basis 5,6,3,1.0666666666666667\n"),
        "last cell of the last image"
    );
}

#[test]
fn bad_figures_and_options_are_errors_not_panics() {
    let all_missing = Figure::chart(
        "Empty",
        Axis::new("x", ""),
        Axis::new("y", ""),
        vec![Series::new("s", vec![f64::NAN], vec![1.0])],
    );
    assert!(matches!(
        render_svg(&all_missing, &RenderOptions::default()),
        Err(FigureError::Invalid(_))
    ));
    let mismatched = Figure::chart(
        "Bad",
        Axis::new("x", ""),
        Axis::new("y", ""),
        vec![Series::new("s", vec![1.0, 2.0], vec![1.0])],
    );
    assert!(matches!(
        render_png(&mismatched, &RenderOptions::default()),
        Err(FigureError::Invalid(_))
    ));
    assert!(to_csv(&mismatched).is_err());
    let tiny = RenderOptions {
        width: 0,
        height: 480,
        dpi: 96.0,
    };
    assert!(matches!(
        render_png(&accuracy_chart(), &tiny),
        Err(FigureError::Options(_))
    ));
    let nan_dpi = RenderOptions {
        width: 640,
        height: 480,
        dpi: f64::NAN,
    };
    assert!(matches!(
        render_svg(&accuracy_chart(), &nan_dpi),
        Err(FigureError::Options(_))
    ));
    let small = RenderOptions {
        width: 64,
        height: 64,
        dpi: 96.0,
    };
    let heat = differential_heatmap(vec![vec![1.0, 2.0]]);
    let err = render_png(&heat, &small).unwrap_err();
    assert!(
        matches!(&err, FigureError::Options(m) if m.contains("too small")),
        "{err}"
    );
    // A log axis skips non-positive values like missing ones.
    let log = Figure::chart(
        "Speed",
        Axis::new("Time", "s").log(),
        Axis::new("Accuracy", ""),
        vec![Series::new("m", vec![0.0, 0.01, 10.0], vec![0.5, 0.6, 0.9])],
    );
    let (texts, _) = parse_svg(&render_svg(&log, &RenderOptions::default()).unwrap());
    assert!(texts.iter().any(|t| t == "m (1 missing)"), "{texts:?}");
}

fn leftovers(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

#[test]
fn unwritable_targets_give_an_error_naming_the_path() {
    let dir = temp_dir("unwritable");
    let fig = accuracy_chart();
    let opts = RenderOptions::default();

    let missing = dir.join("no-such-dir").join("fig.svg");
    let err = write_figure(&fig, &missing, &opts).unwrap_err();
    assert!(
        err.to_string().contains(&missing.display().to_string()),
        "{err}"
    );
    assert!(!missing.exists());

    // A file where a directory should be.
    fs::write(dir.join("plain"), "x").unwrap();
    let under_file = dir.join("plain").join("fig.png");
    let err = write_figure(&fig, &under_file, &opts).unwrap_err();
    assert!(
        matches!(&err, FigureError::Io { path, .. } if path == &under_file),
        "{err}"
    );
    assert_eq!(
        leftovers(&dir),
        vec!["plain".to_string()],
        "nothing half-written"
    );

    let bad_ext = dir.join("fig.jpg");
    assert!(matches!(
        write_figure(&fig, &bad_ext, &opts),
        Err(FigureError::Options(_))
    ));

    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let ro = dir.join("read-only");
        fs::create_dir(&ro).unwrap();
        fs::set_permissions(&ro, fs::Permissions::from_mode(0o555)).unwrap();
        // Root ignores permissions; the check only means something for other users.
        if fs::write(ro.join("probe"), "x").is_err() {
            let target = ro.join("fig.svg");
            let err = write_figure(&fig, &target, &opts).unwrap_err();
            assert!(
                err.to_string().contains(&target.display().to_string()),
                "{err}"
            );
            assert!(leftovers(&ro).is_empty(), "nothing half-written");
        } else {
            eprintln!("running as root: read-only directory check not applicable");
        }
        fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).unwrap();
    }
    fs::remove_dir_all(&dir).unwrap();
}

fn entry(name: &str, figure: Figure) -> FigureEntry {
    FigureEntry {
        name: name.into(),
        figure,
        parameters: BTreeMap::from([
            ("num_bases".to_string(), "64".to_string()),
            ("beta".to_string(), "0.4".to_string()),
        ]),
        session: "icub-grasp".into(),
        date: "2026-11-21".into(),
    }
}

#[test]
fn export_all_writes_every_figure_and_an_index() {
    let dir = temp_dir("export-all").join("out");
    let set = FigureSet {
        entries: vec![
            entry("fig6-accuracy", accuracy_chart()),
            entry("fig8-usage", usage_bars()),
            entry("fig6-bases", basis_grid()),
        ],
    };
    let opts = RenderOptions {
        width: 640,
        height: 480,
        dpi: 96.0,
    };
    let index = export_all(&set, &dir, &[Format::Svg, Format::Png, Format::Csv], &opts).unwrap();
    assert_eq!(index.entries.len(), 3);
    for e in &index.entries {
        assert_eq!(e.files.len(), 3);
        for f in &e.files {
            assert!(fs::metadata(dir.join(f)).unwrap().len() > 0, "{f}");
        }
    }
    assert_eq!(
        png_size(&fs::read(dir.join("fig8-usage.png")).unwrap()),
        (640, 480)
    );
    let md = fs::read_to_string(dir.join("index.md")).unwrap();
    assert!(
        md.contains("| Basis usage per label | [fig8-usage.svg](fig8-usage.svg)"),
        "{md}"
    );
    assert!(
        md.contains("beta = 0.4, num_bases = 64 | icub-grasp | 2026-11-21 |"),
        "{md}"
    );

    // A duplicate name is refused before anything is written.
    let other = dir.with_file_name("dup");
    let dup = FigureSet {
        entries: vec![entry("a", usage_bars()), entry("a", basis_grid())],
    };
    assert!(matches!(
        export_all(&dup, &other, &[Format::Svg], &opts),
        Err(FigureError::Options(_))
    ));
    assert!(!other.exists());
    fs::remove_dir_all(dir.parent().unwrap()).unwrap();
}

/// A figure that cannot be drawn at the export's size is named, and every other figure is
/// written all the same, with the index.
#[test]
fn export_all_names_a_figure_it_cannot_draw_and_writes_the_others() {
    let dir = temp_dir("export-all-not-drawn").join("out");
    // 900 captioned images cannot share a 400 × 300 image.
    let crowded = Figure::image_grid(
        "Nine hundred bases",
        (0..900)
            .map(|k| GridImage {
                caption: format!("basis {k}"),
                values: vec![vec![k as f64; 4]; 7],
            })
            .collect(),
        ColorScale::viridis("Basis weight", ""),
    );
    let set = FigureSet {
        entries: vec![
            entry("accuracy", accuracy_chart()),
            entry("crowded", crowded),
            entry("usage", usage_bars()),
        ],
    };
    let opts = RenderOptions {
        width: 400,
        height: 300,
        dpi: 96.0,
    };
    let index = export_all(&set, &dir, &[Format::Svg, Format::Png], &opts).unwrap();
    let written: Vec<&str> = index.entries.iter().map(|e| e.name.as_str()).collect();
    assert_eq!(written, ["accuracy", "usage"]);
    assert_eq!(index.not_drawn.len(), 1);
    assert_eq!(index.not_drawn[0].name, "crowded");
    assert!(index.not_drawn_text().contains("Nine hundred bases"));
    assert!(!dir.join("crowded.svg").exists() && !dir.join("crowded.png").exists());
    assert!(dir.join("usage.png").exists());
    let md = fs::read_to_string(dir.join("index.md")).unwrap();
    assert!(md.contains("## Not drawn at this size"), "{md}");
    assert!(md.contains("- crowded (Nine hundred bases): "), "{md}");
    fs::remove_dir_all(dir.parent().unwrap()).unwrap();
}

#[test]
fn render_figure_command_renders_a_json_figure() {
    let dir = temp_dir("cli");
    let json = dir.join("fig.json");
    fs::write(&json, serde_json::to_string(&usage_bars()).unwrap()).unwrap();
    let out = dir.join("fig.png");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
        .args([
            "render-figure",
            json.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .args(["--width", "500", "--height", "300", "--dpi", "120"])
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(png_size(&fs::read(&out).unwrap()), (500, 300));

    fs::write(&json, "{\"title\": \"no kind\"}").unwrap();
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_tactile-workbench"))
        .args([
            "render-figure",
            json.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("is not a valid figure"));
    fs::remove_dir_all(&dir).unwrap();
}
