//! `simulate`: regenerate the sample sessions from a seed (byte for byte).

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use crate::session::{self, simulate};

/// The seed of the committed `sample-sessions/`.
pub const SAMPLE_SEED: u64 = 1;
pub const STABILITY_FILE: &str = "grasp-stability.json";
pub const RECOGNITION_FILE: &str = "object-recognition.json";

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Kind {
    /// Both sample sessions.
    All,
    /// Grasp stability: two 4 × 7 pads, 54 objects × 10 picks.
    Stability,
    /// Object recognition: iCub-like hand, 10 objects × 20 grasps.
    Recognition,
}

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Which session to generate.
    #[arg(long, value_enum, default_value_t = Kind::All)]
    pub kind: Kind,
    /// Seed of every random choice (the committed samples use 1).
    #[arg(long, default_value_t = SAMPLE_SEED)]
    pub seed: u64,
    /// Folder to write into (created if missing).
    #[arg(short, long, default_value = "sample-sessions")]
    pub out_dir: PathBuf,
}

pub fn run(args: SimulateArgs) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out_dir)?;
    if matches!(args.kind, Kind::All | Kind::Stability) {
        let path = args.out_dir.join(STABILITY_FILE);
        session::save(&simulate::grasp_stability(args.seed), &path)?;
        println!("written {}", path.display());
    }
    if matches!(args.kind, Kind::All | Kind::Recognition) {
        let path = args.out_dir.join(RECOGNITION_FILE);
        session::save(&simulate::object_recognition(args.seed), &path)?;
        println!("written {}", path.display());
    }
    Ok(())
}
