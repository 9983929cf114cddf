//! What the results leave on disk: models kept in the data folder, saved, loaded and
//! evaluated; projects saved and opened; the results kept between runs; selections saved
//! as sessions.

use super::*;

impl Analyses {
    /// Keep the models in `dir` from now on, and read back those an earlier run kept
    /// there (in the background).
    pub fn keep_models_in(&mut self, ctx: &egui::Context, data: &std::path::Path) {
        let dir = data.join(KEPT_MODELS);
        self.models.dir = Some(dir.clone());
        if !dir.is_dir() {
            return;
        }
        self.spawn(ctx, None, "Reopening the kept models".into(), move |_| {
            let (ok, bad) = crate::app::models::read_dir(&dir);
            Ok(JobOutput::ModelsRestored(ok, bad))
        });
    }

    /// Write the models not yet kept (each atomically, in the background).
    pub fn keep_models(&mut self, ctx: &egui::Context) {
        let mut writes = Vec::new();
        for m in &mut self.models.list {
            if let (Some(path), false) = (&m.kept, m.written) {
                m.written = true;
                writes.push((path.clone(), m.file.clone()));
            }
        }
        for (path, file) in writes {
            self.spawn_bookkeeping(ctx, "Keeping a model".into(), move |_| {
                if let Some(dir) = path.parent() {
                    std::fs::create_dir_all(dir)
                        .map_err(|e| JobError::failed(format!("{}: {e}", dir.display())))?;
                }
                models::save(&file, &path).map_err(JobError::failed)?;
                Ok(JobOutput::Kept)
            });
        }
    }

    /// Remove model `i` from the list and its kept copy from the data folder.
    pub fn remove_model(&mut self, i: usize) {
        if i >= self.models.list.len() {
            return;
        }
        let m = self.models.list.remove(i);
        if let Some(p) = m.kept.filter(|p| p.is_file())
            && let Err(e) = std::fs::remove_file(&p)
        {
            self.notes.error(format!("{}: {e}", p.display()));
        }
        self.models.evaluate = None;
    }

    /// Write model `i` to `path` (in the background).
    pub fn save_model(&mut self, ctx: &egui::Context, i: usize, path: PathBuf) {
        let Some(m) = self.models.list.get(i) else {
            return;
        };
        let file = m.file.clone();
        self.spawn(
            ctx,
            None,
            format!("Save model {}", path.display()),
            move |_| {
                models::save(&file, &path).map_err(JobError::failed)?;
                Ok(JobOutput::Message(format!(
                    "model saved to {}",
                    path.display()
                )))
            },
        );
    }

    /// Read a model file into the list (in the background); a bad file is a toast.
    pub fn load_model(&mut self, ctx: &egui::Context, path: PathBuf) {
        self.spawn(
            ctx,
            None,
            format!("Load model {}", path.display()),
            move |_| {
                let file = models::load(&path).map_err(JobError::failed)?;
                Ok(JobOutput::ModelLoaded(Box::new(file)))
            },
        );
    }

    /// Model `i` on session `s` under `calibration`, as a held-out result of `s` (in the
    /// background); a session the model cannot read fails with the reason.
    pub fn evaluate_model(
        &mut self,
        ctx: &egui::Context,
        i: usize,
        s: &LoadedSession,
        calibration: Calibration,
    ) {
        let Some(m) = self.models.list.get(i) else {
            return;
        };
        let file = m.file.clone();
        let session = s.session.clone();
        let title = format!(
            "Evaluate {} on {}",
            file.provenance.method.title(),
            session.meta.name
        );
        self.spawn(ctx, None, title, move |p| {
            p.set(0.1, "the model's features and decisions on every grasp");
            let r = models::evaluate(&file, &session, calibration).map_err(JobError::failed)?;
            let mut report = models::held_out_report(&r);
            if r.method.task() == crate::catalogue::Task::Stability {
                // The decision value of every grasp, for the focused grasp's tile.
                report.grasp_codes = r
                    .predictions
                    .iter()
                    .filter_map(|g| {
                        Some(crate::experiments::links::GraspCode {
                            grasp: g.grasp,
                            truth: g.truth.clone()?,
                            predicted: g.predicted.clone(),
                            decision: g.decision,
                            patches: Vec::new(),
                        })
                    })
                    .collect();
            }
            Ok(JobOutput::HeldOut(Box::new(report)))
        });
    }

    /// Save `grasps` of `s` as a native session file at `path` (in the background), named
    /// after the file.
    pub fn save_selection(
        &mut self,
        ctx: &egui::Context,
        s: &LoadedSession,
        grasps: Vec<usize>,
        path: PathBuf,
    ) {
        let session = s.session.clone();
        let name = path
            .file_stem()
            .map_or_else(|| "selection".into(), |n| n.to_string_lossy().into_owned());
        self.spawn(
            ctx,
            None,
            format!("Save selection as {}", path.display()),
            move |_| {
                let sub = crate::session::subset_grasps(&session, &grasps, &name)
                    .map_err(JobError::failed)?;
                crate::session::save(&sub, &path).map_err(JobError::failed)?;
                Ok(JobOutput::Message(format!(
                    "{} grasps of {} saved as the session {name} ({})",
                    sub.grasps.len(),
                    session.meta.name,
                    path.display()
                )))
            },
        );
    }

    /// Read the results an earlier run kept in `path` (in the background).
    pub fn restore_results(&mut self, ctx: &egui::Context, path: PathBuf) {
        self.spawn(
            ctx,
            None,
            "Reopening the last run's results".into(),
            move |_| {
                let project = crate::project::Project::load(&path).map_err(JobError::failed)?;
                Ok(JobOutput::Restored(project))
            },
        );
    }

    /// Write the results (with `sessions`, their sources) to the data folder once they have
    /// changed and no earlier write is still running; atomically, so a crash mid-write leaves
    /// the previous file.
    pub fn keep_if_changed(&mut self, ctx: &egui::Context, sessions: Vec<String>) {
        let Some(path) = self.keep.clone() else {
            return;
        };
        let restoring = self.jobs.iter().any(|j| j.title.starts_with("Reopening"));
        if !self.keep_pending || restoring || self.jobs.iter().any(|j| j.title == KEEP_JOB) {
            return;
        }
        self.keep_pending = false;
        let project = crate::project::Project::new(sessions, self.results.clone())
            .with_frontiers(self.frontiers.clone());
        self.spawn_bookkeeping(ctx, KEEP_JOB.into(), move |_| {
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir)
                    .map_err(|e| JobError::failed(format!("{}: {e}", dir.display())))?;
            }
            project.save(&path).map_err(JobError::failed)?;
            Ok(JobOutput::Kept)
        });
    }

    /// Save the results, their models and the sessions they came from as a project file (in
    /// the background).
    pub fn save_project(&mut self, ctx: &egui::Context, path: PathBuf, sessions: Vec<String>) {
        let models = self.models.list.iter().map(|m| m.file.clone()).collect();
        let project = crate::project::Project::new(sessions, self.results.clone())
            .with_frontiers(self.frontiers.clone())
            .with_models(models);
        self.spawn(
            ctx,
            None,
            format!("Save project {}", path.display()),
            move |_| {
                project.save(&path).map_err(JobError::failed)?;
                Ok(JobOutput::Message(format!(
                    "project saved to {}",
                    path.display()
                )))
            },
        );
    }

    /// Add the results of a saved project (read in the background).
    pub fn open_project(&mut self, ctx: &egui::Context, path: PathBuf) {
        self.spawn(
            ctx,
            None,
            format!("Open project {}", path.display()),
            move |_| {
                let mut project = crate::project::Project::load(&path).map_err(JobError::failed)?;
                // Only sessions: a path into a system folder or to some other file is
                // refused by name, never opened.
                let mut refused = Vec::new();
                project.sessions.retain(|label| {
                    match crate::app::loader::Source::from_label(label).refusal() {
                        Some(why) => {
                            refused.push(why);
                            false
                        }
                        None => true,
                    }
                });
                Ok(JobOutput::Project(project, refused))
            },
        );
    }
}
