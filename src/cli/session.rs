//! `info`, `validate`, `import` and `subset` (a session's grasps of some objects, trials
//! or labels): session files from the shell.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};

use crate::session::{self, Session, SubsetSpec, Trials, icub::IcubOptions};

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A native session file (.json).
    pub file: PathBuf,
}

#[derive(Args, Debug)]
pub struct ValidateArgs {
    /// Native session files to check.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

#[derive(Args, Debug)]
pub struct ImportArgs {
    #[command(subcommand)]
    pub source: ImportSource,
}

#[derive(Subcommand, Debug)]
pub enum ImportSource {
    /// The iCub grasp dataset folder (10 objects × 20 trials).
    Icub {
        /// The dataset folder (holding iCubGraspDataset/ or the trial files).
        dir: PathBuf,
        /// Write the native session here.
        #[arg(short, long)]
        output: PathBuf,
        /// Also import the `full_coke` class, which the dataset's README calls unreliable.
        #[arg(long)]
        include_full_coke: bool,
    },
    /// A BioTac SP grasp CSV of the BTS3 set (e.g. the palm-down grasps).
    Bts3 {
        /// The CSV file.
        csv: PathBuf,
        /// Write the native session here.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// A ROS 2 bag (MCAP) described by an import spec (docs/import.md).
    Mcap {
        /// A .mcap file, or a bag folder as `ros2 bag record` writes it.
        bag: PathBuf,
        /// Write the native session here.
        #[arg(short, long)]
        output: PathBuf,
        /// The import spec (JSON): sensors, joints, label sets, how grasps are cut.
        #[arg(long)]
        spec: PathBuf,
    },
    /// A long-format CSV (one row per frame), or a folder of trial files (one CSV per grasp),
    /// described by an import spec (docs/import.md).
    Csv {
        /// The CSV file, or the folder of trial files.
        file: PathBuf,
        /// Write the native session here.
        #[arg(short, long)]
        output: PathBuf,
        /// The import spec (JSON): sensors, joints, label sets.
        #[arg(long)]
        spec: PathBuf,
    },
}

/// A human-readable summary of a session.
pub fn summary(s: &Session) -> String {
    let mut out = String::new();
    let push = |out: &mut String, line: String| {
        out.push_str(&line);
        out.push('\n');
    };
    push(&mut out, format!("session   {}", s.meta.name));
    push(&mut out, format!("source    {}", s.meta.source));
    if let Some(hz) = s.meta.frame_rate_hz {
        push(&mut out, format!("rate      {hz} Hz"));
    }
    push(&mut out, format!("sensors   {}", s.sensors.len()));
    for sensor in &s.sensors {
        push(
            &mut out,
            format!(
                "  {:<8} {:>2} taxels  {}; pressure = {}",
                sensor.name,
                sensor.layout.taxel_count(),
                sensor.unit,
                sensor.transform.describe()
            ),
        );
    }
    push(&mut out, format!("encoders  {}", s.encoders.len()));
    let frames: Vec<usize> = s.grasps.iter().map(|g| g.frames.len()).collect();
    push(
        &mut out,
        format!(
            "grasps    {} on {} objects; frames per grasp {}–{}",
            s.grasps.len(),
            s.objects().len(),
            frames.iter().min().unwrap_or(&0),
            frames.iter().max().unwrap_or(&0)
        ),
    );
    for (l, set) in s.label_sets.iter().enumerate() {
        let mut counts = vec![0usize; set.classes.len()];
        for g in &s.grasps {
            counts[g.labels[l]] += 1;
        }
        let parts: Vec<String> = set
            .classes
            .iter()
            .zip(&counts)
            .map(|(c, n)| format!("{c} {n}"))
            .collect();
        push(
            &mut out,
            format!("labels    {}: {}", set.name, parts.join(", ")),
        );
    }
    if !s.meta.licence.is_empty() {
        push(
            &mut out,
            format!("licence   {}", s.meta.licence.lines().next().unwrap_or("")),
        );
    }
    out
}

pub fn info(args: InfoArgs) -> anyhow::Result<()> {
    let s = session::load(&args.file)?;
    print!("{}", summary(&s));
    Ok(())
}

pub fn validate(args: ValidateArgs) -> anyhow::Result<()> {
    let mut failed = 0;
    for f in &args.files {
        match session::load(f) {
            Ok(s) => println!("{}: ok ({} grasps)", f.display(), s.grasps.len()),
            Err(e) => {
                eprintln!("{e}");
                failed += 1;
            }
        }
    }
    anyhow::ensure!(
        failed == 0,
        "{failed} of {} files failed validation",
        args.files.len()
    );
    Ok(())
}

fn write(s: &Session, output: &Path) -> anyhow::Result<()> {
    session::save(s, output)?;
    print!("{}", summary(s));
    println!("written   {}", output.display());
    Ok(())
}

/// Refuse an output that is one of `inputs`, or inside `folder` (an input folder the import
/// reads as a whole).
fn refuse(output: &Path, inputs: &[&Path], folder: &Path) -> anyhow::Result<()> {
    crate::fsutil::refuse_input_as_output(output, inputs)?;
    crate::fsutil::refuse_output_inside(output, folder)?;
    Ok(())
}

pub fn import(args: ImportArgs) -> anyhow::Result<()> {
    match args.source {
        ImportSource::Icub {
            dir,
            output,
            include_full_coke,
        } => {
            refuse(&output, &[&dir], &dir)?;
            let s = session::import_icub_with(&dir, &IcubOptions { include_full_coke })
                .with_context(|| format!("importing the iCub dataset from {}", dir.display()))?;
            write(&s, &output)
        }
        ImportSource::Bts3 { csv, output } => {
            refuse(&output, &[&csv], &csv)?;
            let s = session::import_bts3(&csv)
                .with_context(|| format!("importing BTS3 grasps from {}", csv.display()))?;
            write(&s, &output)
        }
        ImportSource::Mcap {
            bag,
            output,
            spec: spec_path,
        } => {
            let spec = session::ImportSpec::load(&spec_path)?;
            // The bag, each of its files, the spec and its windows CSV.
            let files = session::bag::bag_files(&bag).unwrap_or_default();
            let mut inputs: Vec<&Path> = vec![&bag, &spec_path];
            inputs.extend(files.iter().map(PathBuf::as_path));
            if let Some(session::spec::GraspCut::Windows(csv)) = &spec.cut {
                inputs.push(csv);
            }
            refuse(&output, &inputs, &bag)?;
            let s = session::ros2::import_bag(&bag, &spec)
                .with_context(|| format!("importing the ROS 2 bag {}", bag.display()))?;
            write(&s, &output)
        }
        ImportSource::Csv {
            file,
            output,
            spec: spec_path,
        } => {
            if file.is_dir() {
                // The folder, the spec and every trial file.
                let files = session::trial_folder::trial_files(&file).unwrap_or_default();
                let mut inputs: Vec<&Path> = vec![&file, &spec_path];
                inputs.extend(files.iter().map(|f| f.path.as_path()));
                refuse(&output, &inputs, &file)?;
                let spec = session::ImportSpec::load(&spec_path)?;
                let s = session::trial_folder::import_trial_folder(&file, &spec)
                    .with_context(|| format!("importing the trial folder {}", file.display()))?;
                return write(&s, &output);
            }
            refuse(&output, &[&file, &spec_path], &file)?;
            let spec = session::ImportSpec::load(&spec_path)?;
            let s = session::long_csv::import_long_csv(&file, &spec)
                .with_context(|| format!("importing the long-format CSV {}", file.display()))?;
            write(&s, &output)
        }
    }
}

#[derive(Args, Debug)]
pub struct SubsetArgs {
    pub session: PathBuf,
    /// Keep these objects (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub objects: Vec<String>,
    /// Keep these trial numbers: a list `1,2,5` and/or ranges `1..10` (inclusive).
    #[arg(long)]
    pub trials: Option<String>,
    /// Keep grasps of these classes: `SET=CLASS,…` (classes of one set: any of them).
    #[arg(long, value_delimiter = ',')]
    pub labels: Vec<String>,
    /// The new session's name (default: the output file's stem).
    #[arg(long)]
    pub name: Option<String>,
    /// The session file to write (native format).
    #[arg(short, long, value_name = "OUT.json")]
    pub output: PathBuf,
}

/// Parse `1,2,5` / `1..10` (inclusive) trial numbers; a range stays a range. An empty
/// list or item (`''`, `1,,2`) is refused: it would keep every trial or hide a typo.
fn parse_trials(s: &str) -> anyhow::Result<Trials> {
    if s.trim().is_empty() {
        bail!("--trials: empty; give trial numbers (`1,2,5`, `1..10`) or leave the option out");
    }
    let mut ranges = Vec::new();
    for item in s.split(',').map(str::trim) {
        let bad = || format!("--trials: bad item {item:?} in {s:?} (expected N or A..B)");
        if item.is_empty() {
            bail!(bad());
        }
        match item.split_once("..") {
            Some((a, b)) => {
                let (a, b): (u32, u32) = (
                    a.trim().parse().with_context(bad)?,
                    b.trim_start_matches('=').trim().parse().with_context(bad)?,
                );
                if a > b {
                    bail!(bad());
                }
                ranges.push(a..=b);
            }
            None => {
                let n: u32 = item.parse().with_context(bad)?;
                ranges.push(n..=n);
            }
        }
    }
    Ok(Trials::new(ranges))
}

pub fn subset(a: SubsetArgs) -> anyhow::Result<()> {
    super::refuse_input_as_output(Some(&a.output), &[&a.session])?;
    let labels = a
        .labels
        .iter()
        .map(|l| {
            l.split_once('=')
                .map(|(s, c)| (s.trim().to_string(), c.trim().to_string()))
                .with_context(|| format!("--labels: {l:?} is not SET=CLASS"))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let spec = SubsetSpec {
        objects: a.objects.clone(),
        trials: a
            .trials
            .as_deref()
            .map(parse_trials)
            .transpose()?
            .unwrap_or_default(),
        labels,
    };
    let source =
        session::open(&a.session).with_context(|| format!("opening {}", a.session.display()))?;
    let name = a
        .name
        .clone()
        .unwrap_or_else(|| session::file_stem(&a.output));
    let sub = session::subset(&source, &spec, &name)?;
    session::save(&sub, &a.output)?;
    println!(
        "{}: {} of {} grasps ({}); wrote {}",
        sub.meta.name,
        sub.grasps.len(),
        source.grasps.len(),
        spec.describe(),
        a.output.display()
    );
    Ok(())
}
