//! "Run on a cluster…": the form's run written as a sharded sweep plan (docs/cluster.md)
//! instead of run here: plan.json, a copy of the session and a Slurm job-array script, for
//! `sbatch` on the cluster and `sweep merge` afterwards, whose project opens here like any
//! result.

use std::path::{Path, PathBuf};

use super::{Cx, Room};
use crate::app::results::JobOutput;
use crate::experiments::result::slug;
use crate::jobs::JobError;
use crate::sweep::{self, PlanRequest, SBATCH_FILE};

/// The plan's settings, shared by the views (a cluster is the same whichever view plans).
#[derive(Clone, Debug)]
pub struct SlurmForm {
    pub shards: usize,
    /// The plan folder; empty: `sweeps/<experiment>-<session>` under the current folder.
    pub folder: String,
    /// The program as the cluster's tasks call it.
    pub program: String,
    pub partition: String,
}

impl Default for SlurmForm {
    fn default() -> Self {
        SlurmForm {
            shards: 4,
            folder: String::new(),
            program: "tactile-workbench".into(),
            partition: String::new(),
        }
    }
}

impl SlurmForm {
    fn folder_for(&self, experiment: &str, session: &str) -> PathBuf {
        if self.folder.trim().is_empty() {
            Path::new("sweeps").join(format!("{experiment}-{}", slug(session)))
        } else {
            PathBuf::from(self.folder.trim())
        }
    }
}

/// The section under a room's form; nothing for rooms whose runs do not shard.
pub fn ui(ui: &mut egui::Ui, room: &dyn Room, cx: &mut Cx) {
    let Some(experiment) = room.sweep(cx) else {
        return;
    };
    let Some(session) = cx.session() else { return };
    let name = session.session.meta.name.clone();
    let source = session.source.label();
    let data = session.session.clone();
    ui.separator();
    egui::CollapsingHeader::new("Run on a cluster…")
        .id_salt("run-on-a-cluster")
        .show(ui, |ui| {
            ui.small(
                "Writes this run as a sweep plan for a Slurm job array instead of running \
                 it here (docs/cluster.md).",
            );
            let f = &mut *cx.slurm;
            ui.add(
                egui::DragValue::new(&mut f.shards)
                    .range(1..=1000)
                    .prefix("shards "),
            );
            let label = ui.label("Plan folder");
            let experiment_name = match &experiment {
                Ok(e) => e.name(),
                Err(_) => "sweep",
            };
            let default = f.folder_for(experiment_name, &name);
            ui.add(
                egui::TextEdit::singleline(&mut f.folder).hint_text(default.display().to_string()),
            )
            .labelled_by(label.id);
            let label = ui.label("Program on the cluster");
            ui.text_edit_singleline(&mut f.program)
                .labelled_by(label.id);
            let label = ui.label("Partition (optional)");
            ui.text_edit_singleline(&mut f.partition)
                .labelled_by(label.id);
            let experiment = match experiment {
                Ok(e) => e,
                Err(why) => {
                    ui.label(why);
                    return;
                }
            };
            if !ui.button("Write plan").clicked() {
                return;
            }
            let dir = std::path::absolute(&default).unwrap_or(default);
            let request = PlanRequest {
                shards: f.shards,
                source,
                time_minutes: None,
                cpus: None,
                mem_mb: None,
                partition: Some(f.partition.trim().to_string()).filter(|p| !p.is_empty()),
                program: f.program.trim().to_string(),
            };
            // Copying a large session takes a moment: write in the background.
            let ctx = cx.ctx.clone();
            cx.analyses.spawn(
                &ctx,
                None,
                format!("Plan a {experiment_name} sweep of {name}"),
                move |_| {
                    let plan = sweep::write_plan(&dir, &data, experiment, &request)
                        .map_err(JobError::failed)?;
                    let r = &plan.resources;
                    Ok(JobOutput::Message(format!(
                        "Wrote a {} sweep of {} items in {} shards into {} (each task: {} CPUs, \
                         {} MB, up to {}). On the cluster: sbatch {}; then `tactile-workbench \
                         sweep merge {} -o result.json --project project.json` and open the \
                         project here.",
                        plan.experiment.name(),
                        plan.items.len(),
                        plan.shard_count(),
                        dir.display(),
                        r.cpus,
                        r.mem_mb,
                        r.time_text(),
                        dir.join(SBATCH_FILE).display(),
                        dir.display(),
                    )))
                },
            );
        });
}
