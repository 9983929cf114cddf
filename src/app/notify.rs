//! Notifications: toasts in a corner that fade after a few seconds (errors stay until
//! dismissed), and the full log in a window from the View menu.

use egui::{Align2, Color32, RichText};

/// How long an informational toast stays, in seconds.
pub const TOAST_SECONDS: f64 = 5.0;
/// At most this many toasts are stacked at once; older ones stay in the log.
const MAX_TOASTS: usize = 4;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Info,
    Error,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    pub level: Level,
    pub text: String,
    /// UI time (seconds, `egui::InputState::time`) when it was posted.
    pub time: f64,
    /// Still shown as a toast.
    pub toast: bool,
}

#[derive(Default)]
pub struct Notifications {
    pub log: Vec<Entry>,
    pub log_open: bool,
    /// Posted but not yet stamped with the UI time (stamped at the next frame).
    pending: Vec<(Level, String)>,
}

impl Notifications {
    pub fn info(&mut self, text: impl Into<String>) {
        self.pending.push((Level::Info, text.into()));
    }

    pub fn error(&mut self, text: impl Into<String>) {
        self.pending.push((Level::Error, text.into()));
    }

    /// Every message so far, oldest first (those not yet stamped included).
    pub fn texts(&self) -> Vec<String> {
        self.log
            .iter()
            .map(|e| e.text.clone())
            .chain(self.pending.iter().map(|(_, t)| t.clone()))
            .collect()
    }

    /// The errors so far, oldest first (those not yet stamped included).
    pub fn errors(&self) -> Vec<String> {
        self.log
            .iter()
            .filter(|e| e.level == Level::Error)
            .map(|e| e.text.clone())
            .chain(
                self.pending
                    .iter()
                    .filter(|(l, _)| *l == Level::Error)
                    .map(|(_, t)| t.clone()),
            )
            .collect()
    }

    /// The toasts on screen now.
    pub fn toasts(&self) -> impl Iterator<Item = &Entry> {
        self.log.iter().filter(|e| e.toast)
    }

    /// Stamp new entries and retire informational toasts older than [`TOAST_SECONDS`].
    /// Returns true while a toast will fade (the UI should repaint).
    pub fn tick(&mut self, now: f64) -> bool {
        for (level, text) in self.pending.drain(..) {
            self.log.push(Entry {
                level,
                text,
                time: now,
                toast: true,
            });
        }
        let mut fading = false;
        for e in &mut self.log {
            if e.toast && e.level == Level::Info {
                if now - e.time >= TOAST_SECONDS {
                    e.toast = false;
                } else {
                    fading = true;
                }
            }
        }
        // Keep the stack short: the oldest informational toasts leave first.
        let mut shown = self.log.iter().filter(|e| e.toast).count();
        for e in &mut self.log {
            if shown <= MAX_TOASTS {
                break;
            }
            if e.toast && e.level == Level::Info {
                e.toast = false;
                shown -= 1;
            }
        }
        fading
    }

    /// Draw the toasts (bottom right) and, when open, the log window.
    pub fn ui(&mut self, ctx: &egui::Context, now: f64) {
        let toasts: Vec<usize> = (0..self.log.len()).filter(|&i| self.log[i].toast).collect();
        if !toasts.is_empty() {
            egui::Area::new(egui::Id::unique("toasts"))
                .anchor(Align2::RIGHT_BOTTOM, egui::vec2(-12.0, -12.0))
                .order(egui::Order::Foreground)
                .interactable(true)
                .show(ctx, |ui| {
                    // Never wider than the window: long messages wrap instead of running off
                    // its left edge.
                    let width = (ctx.content_rect().width() - 48.0).clamp(120.0, 420.0);
                    ui.set_max_width(width);
                    for i in toasts {
                        let e = &mut self.log[i];
                        // Fade over the last second of an informational toast.
                        let alpha = match e.level {
                            Level::Info => {
                                ((TOAST_SECONDS - (now - e.time)).clamp(0.0, 1.0)) as f32
                            }
                            Level::Error => 1.0,
                        };
                        let frame = egui::Frame::popup(ui.style()).multiply_with_opacity(alpha);
                        frame.show(ui, |ui| {
                            ui.set_max_width(width);
                            let color = match e.level {
                                Level::Info => ui.visuals().text_color(),
                                Level::Error => ui.visuals().error_fg_color,
                            };
                            let text = RichText::new(&e.text).color(color.gamma_multiply(alpha));
                            ui.add(egui::Label::new(text).wrap());
                            if ui.small_button("Dismiss").clicked() {
                                e.toast = false;
                            }
                        });
                    }
                });
        }
        let mut open = self.log_open;
        egui::Window::new("Notification log")
            .open(&mut open)
            .default_size([560.0, 320.0])
            .show(ctx, |ui| {
                if self.log.is_empty() {
                    ui.label("Nothing yet.");
                }
                egui::ScrollArea::vertical()
                    .stick_to_bottom(true)
                    .show(ui, |ui| {
                        for e in &self.log {
                            let color = match e.level {
                                Level::Info => ui.visuals().text_color(),
                                Level::Error => ui.visuals().error_fg_color,
                            };
                            ui.horizontal_wrapped(|ui| {
                                ui.label(
                                    RichText::new(format!("{:>7.1} s", e.time))
                                        .monospace()
                                        .color(Color32::GRAY),
                                );
                                ui.label(RichText::new(&e.text).color(color));
                            });
                        }
                    });
            });
        self.log_open = open;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn info_fades_error_stays_log_keeps_both() {
        let mut n = Notifications::default();
        n.info("exported");
        n.error("failed: no such file");
        assert!(n.tick(10.0));
        assert_eq!(n.toasts().count(), 2);
        n.tick(10.0 + TOAST_SECONDS + 0.1);
        let left: Vec<_> = n.toasts().map(|e| e.text.as_str()).collect();
        assert_eq!(left, ["failed: no such file"]);
        assert_eq!(n.log.len(), 2);
    }

    #[test]
    fn the_stack_keeps_errors_and_drops_the_oldest_info() {
        let mut n = Notifications::default();
        n.error("e");
        for i in 0..6 {
            n.info(format!("i{i}"));
        }
        n.tick(0.0);
        let shown: Vec<_> = n.toasts().map(|e| e.text.as_str()).collect();
        assert_eq!(shown, ["e", "i3", "i4", "i5"]);
    }
}
