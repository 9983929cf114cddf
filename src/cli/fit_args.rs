//! `fit`'s command line: a subcommand per method of the catalogue, with the options of
//! its kind of fit (the fitting itself is in `model`).

use std::path::PathBuf;

use clap::{Args, FromArgMatches};

use super::stability::StabilityArgs;
use crate::catalogue::{Classifier, Input, MethodId, Task};
use crate::experiments::feature_choice::AUTO_FOLDS;

/// `fit METHOD SESSION -o MODEL.json …`: a subcommand per method of the catalogue, named
/// as `frontier --method` names it, with the options of its kind of fit.
#[derive(Debug)]
pub struct FitArgs {
    pub method: MethodId,
    pub options: FitOptions,
}

/// A method's options, by its kind of fit.
#[derive(Debug)]
pub enum FitOptions {
    Stability(FitStabilityArgs),
    Sequences(FitSequenceArgs),
    Clusters(FitClusterArgs),
    TableOne(FitTableOneArgs),
    /// A registered method: its own command's options (built from its declared knobs).
    Registered(clap::ArgMatches),
}

/// How a method is fitted, from what the catalogue says it learns and reads.
#[derive(Clone, Copy)]
enum FitKind {
    Stability,
    Sequences,
    Clusters,
    TableOne,
    Registered(&'static dyn Classifier),
}

impl FitKind {
    fn of(method: MethodId) -> FitKind {
        if let Some(c) = method.classifier() {
            return FitKind::Registered(c);
        }
        match (method.task(), method.input()) {
            (Task::Stability, _) => FitKind::Stability,
            (_, Input::TableOne) => FitKind::TableOne,
            (Task::Clustering, _) => FitKind::Clusters,
            (Task::Recognition, _) => FitKind::Sequences,
        }
    }

    /// What `fit --help` says of a method of this kind, after its title.
    fn about(self) -> &'static str {
        match self {
            FitKind::Stability => {
                "on the key-frame patches, with the options of `stability`: one \
                 configuration, or a grid's parsimonious choice"
            }
            FitKind::Sequences => {
                "experts taught every grasp in the protocol's order; `--from` teaches a \
                 saved model further"
            }
            FitKind::Clusters => {
                "experts clustering at a novelty threshold; `--from` learns a saved model \
                 further (novel objects open clusters)"
            }
            FitKind::TableOne => {
                "on the per-grasp Table I features (k-means and the SOM: `--k` centres or \
                 units; the RBF SVM: C and gamma chosen by the `baselines` grid)"
            }
            FitKind::Registered(_) => "with its size knobs as options",
        }
    }
}

/// The `fit` subcommand of `method`.
fn fit_command(method: MethodId) -> clap::Command {
    let info = method.info();
    let kind = FitKind::of(method);
    let cmd = clap::Command::new(info.key);
    let cmd = match kind {
        FitKind::Stability => FitStabilityArgs::augment_args(cmd),
        FitKind::Sequences => FitSequenceArgs::augment_args(cmd),
        FitKind::Clusters => FitClusterArgs::augment_args(cmd),
        FitKind::TableOne => FitTableOneArgs::augment_args(cmd),
        FitKind::Registered(c) => registered_command(cmd, c),
    };
    cmd.visible_aliases(info.aliases.iter().copied())
        .about(format!("{} {}", info.title, kind.about()))
}

impl Args for FitArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        cmd.subcommand_required(true)
            .subcommands(MethodId::all().map(fit_command))
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl FromArgMatches for FitArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        use clap::error::ErrorKind;
        let (name, sub) = m
            .subcommand()
            .ok_or_else(|| clap::Error::new(ErrorKind::MissingSubcommand))?;
        // clap names the subcommand by its key whatever alias was typed.
        let method: MethodId = name
            .parse()
            .map_err(|_| clap::Error::new(ErrorKind::InvalidSubcommand))?;
        let options = match FitKind::of(method) {
            FitKind::Stability => FitOptions::Stability(FitStabilityArgs::from_arg_matches(sub)?),
            FitKind::Sequences => FitOptions::Sequences(FitSequenceArgs::from_arg_matches(sub)?),
            FitKind::Clusters => FitOptions::Clusters(FitClusterArgs::from_arg_matches(sub)?),
            FitKind::TableOne => FitOptions::TableOne(FitTableOneArgs::from_arg_matches(sub)?),
            FitKind::Registered(_) => FitOptions::Registered(sub.clone()),
        };
        Ok(FitArgs { method, options })
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

#[derive(Args, Debug)]
pub struct FitTableOneArgs {
    pub session: PathBuf,
    /// Centres (k-means) or units (SOM); the paper's 10.
    #[arg(long, default_value_t = 10)]
    pub k: usize,
    /// The label set learned (RBF SVM) or scored against (k-means, SOM).
    #[arg(long, default_value = "object")]
    pub target: String,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[arg(short, long, value_name = "MODEL.json")]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct FitClusterArgs {
    pub session: PathBuf,
    /// The novelty threshold (e.g. the one `clustering --choose-threshold stability`
    /// chose without labels); required unless --from.
    #[arg(long)]
    pub threshold: Option<f64>,
    /// Feature families per step, as for `fit ds` (default `auto`: chosen by cross
    /// validation of DU's (GU's) experts, DS (GS), on SESSION).
    #[arg(long)]
    pub features: Option<String>,
    /// The label set clusters are scored against by `evaluate` (default `object`; never
    /// read while learning).
    #[arg(long)]
    pub target: Option<String>,
    /// Seed of the learning order.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Learn this saved model further on SESSION.
    #[arg(long, value_name = "MODEL.json")]
    pub from: Option<PathBuf>,
    /// With --from: teach the grasps one at a time in the session's order, as a live
    /// stream teaches them (`live --teach`), instead of the protocol's seeded shuffle.
    #[arg(long, requires = "from")]
    pub in_order: bool,
    #[arg(short, long, value_name = "MODEL.json")]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct FitSequenceArgs {
    pub session: PathBuf,
    /// Feature families per step (`auto`, `all`, `moments`, `encoders`, `raw`, `change`, or
    /// combinations such as `raw+encoders`; default `auto`: the family with the fewest
    /// features within one standard error of the best 5-fold accuracy on SESSION).
    #[arg(long)]
    pub features: Option<String>,
    /// The label set to learn (default `object`).
    #[arg(long)]
    pub target: Option<String>,
    /// Seed of the training order.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Basis vectors per expert (default: the paper's 50).
    #[arg(long)]
    pub capacity: Option<usize>,
    /// Steps of input history (default: the paper's 15).
    #[arg(long)]
    pub tau: Option<usize>,
    /// Switch off hyperparameter adaptation.
    #[arg(long)]
    pub no_adapt: bool,
    /// Teach this saved model further on SESSION (its features, target, size and range
    /// stay; a class it has not seen gets a new expert).
    #[arg(long, value_name = "MODEL.json")]
    pub from: Option<PathBuf>,
    /// With --from: teach the grasps one at a time in the session's order, as a live
    /// stream teaches them (`live --teach`), instead of the protocol's seeded shuffle.
    #[arg(long, requires = "from")]
    pub in_order: bool,
    /// The model file to write.
    #[arg(short, long, value_name = "MODEL.json")]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct FitStabilityArgs {
    #[command(flatten)]
    pub stability: StabilityArgs,
    /// The model file to write.
    #[arg(short, long, value_name = "MODEL.json")]
    pub output: PathBuf,
}

/// The command line of a registered method, built from its declared knobs.
fn registered_command(cmd: clap::Command, c: &dyn Classifier) -> clap::Command {
    use clap::{Arg, value_parser};
    let info = c.info();
    let mut cmd = cmd
        .arg(
            Arg::new("session")
                .value_name("SESSION")
                .required(true)
                .value_parser(value_parser!(PathBuf)),
        )
        .arg(
            Arg::new("output")
                .short('o')
                .long("output")
                .value_name("MODEL.json")
                .required(true)
                .value_parser(value_parser!(PathBuf)),
        )
        .arg(
            Arg::new("features")
                .long("features")
                .default_value("auto")
                .help(format!(
                    "Feature families per step: auto (the family with the fewest features \
                     within one standard error of the best {AUTO_FOLDS}-fold accuracy on \
                     SESSION), or a set as for `fit ds` (the method's own: {})",
                    c.features()
                )),
        )
        .arg(
            Arg::new("target")
                .long("target")
                .default_value("object")
                .help("The label set to learn"),
        )
        .arg(
            Arg::new("seed")
                .long("seed")
                .default_value("0")
                .value_parser(value_parser!(u64)),
        );
    for (k, v) in info.size_knobs.iter().zip(c.default_size()) {
        cmd = cmd.arg(
            Arg::new(k.name)
                .long(k.name)
                .value_parser(value_parser!(f64))
                .help(format!("{} (default {v})", k.meaning)),
        );
    }
    cmd
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::super::{Cli, Command};
    use super::*;

    fn parsed(args: &[&str]) -> Result<FitArgs, clap::Error> {
        let all = [&["tactile-workbench", "fit"], args].concat();
        match Cli::try_parse_from(all)?.command {
            Some(Command::Fit(a)) => Ok(a),
            other => panic!("not parsed as `fit`: {other:?}"),
        }
    }

    /// Every method of the catalogue is a `fit` subcommand by its key and its aliases, with
    /// the options of what it learns and reads.
    #[test]
    fn every_method_is_fitted_with_the_options_of_its_kind() {
        for m in MethodId::all() {
            let info = m.info();
            for name in std::iter::once(info.key).chain(info.aliases.iter().copied()) {
                let a = parsed(&[name, "s.json", "-o", "m.json"]).unwrap();
                assert_eq!(a.method, m, "`fit {name}`");
                let kind = match a.options {
                    FitOptions::Stability(_) => (Task::Stability, None),
                    FitOptions::Sequences(_) => (Task::Recognition, Some(Input::Sequences)),
                    FitOptions::Clusters(_) => (Task::Clustering, Some(Input::Sequences)),
                    FitOptions::TableOne(_) => (m.task(), Some(Input::TableOne)),
                    FitOptions::Registered(_) => {
                        assert!(m.classifier().is_some(), "{m}");
                        continue;
                    }
                };
                assert!(m.classifier().is_none(), "{m}");
                assert_eq!(kind.0, m.task(), "{m}");
                if let Some(input) = kind.1 {
                    assert_eq!(input, m.input(), "{m}");
                }
            }
        }
    }

    #[test]
    fn a_kinds_options_are_its_own() {
        // DS reads --capacity; DU does not, and k-means has no --threshold.
        let a = parsed(&["ds", "s.json", "-o", "m.json", "--capacity", "7"]).unwrap();
        assert!(matches!(a.options, FitOptions::Sequences(f) if f.capacity == Some(7)));
        assert!(parsed(&["du", "s.json", "-o", "m.json", "--capacity", "7"]).is_err());
        assert!(parsed(&["kmeans", "s.json", "-o", "m.json", "--threshold", "0.3"]).is_err());
        let a = parsed(&["gu", "s.json", "-o", "m.json", "--threshold", "0.3"]).unwrap();
        assert!(matches!(a.options, FitOptions::Clusters(f) if f.threshold == Some(0.3)));
        // A registered method's knob, and a name that is no method.
        let registered = MethodId::all().find_map(|m| m.classifier()).unwrap();
        let knob = registered.info().size_knobs[0].name;
        let a = parsed(&[
            registered.info().key,
            "s.json",
            "-o",
            "m.json",
            &format!("--{knob}"),
            "3",
        ])
        .unwrap();
        let FitOptions::Registered(m) = a.options else {
            panic!(
                "{} not fitted as a registered method",
                registered.info().key
            );
        };
        assert_eq!(m.get_one::<f64>(knob), Some(&3.0));
        assert!(parsed(&["no-such-method", "s.json", "-o", "m.json"]).is_err());
    }
}
