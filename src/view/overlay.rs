//! The viewer's overlay (egui): per-pass GPU times, light statistics, the current error,
//! and the controls: graph variant, camera mode, exposure.

use super::camera::CameraMode;
use crate::render::{CullingReport, LightStats};
use std::path::PathBuf;

/// What the overlay shows; refreshed by the viewer.
#[derive(Default)]
pub(crate) struct FrameInfo {
    pub adapter: String,
    pub scene: String,
    pub lights: usize,
    pub(crate) render_size: [u32; 2],
    /// Smoothed GPU milliseconds per pass; `None` without timestamp queries.
    pub(crate) pass_ms: Option<Vec<(String, f64)>>,
    /// Smoothed CPU milliseconds per displayed frame.
    pub(crate) frame_ms: f64,
    pub(crate) culling: Vec<CullingReport>,
    pub(crate) light_stats: Option<LightStats>,
    /// The error of the last reload (file:line), shown until a good save.
    pub(crate) error: Option<String>,
    /// The last successful reload, for example "lighting.wgsl: 85 ms".
    pub(crate) last_reload: Option<String>,
}

/// A change the user asked for this frame.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum OverlayAction {
    SelectGraph(PathBuf),
    CameraMode(CameraMode),
    /// Add or drop the per-pixel light statistics pass.
    LightStats(bool),
}

pub(crate) struct Overlay {
    /// Graph files offered as variants, with the one in use.
    pub(crate) graphs: Vec<PathBuf>,
    pub(crate) current_graph: PathBuf,
    pub(crate) camera_mode: CameraMode,
    pub exposure_ev: f32,
    pub(crate) visible: bool,
    pub(crate) light_stats: bool,
}

fn graph_label(path: &std::path::Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

impl Overlay {
    /// Draws the overlay and returns what the user changed.
    pub(crate) fn ui(&mut self, ctx: &egui::Context, info: &FrameInfo) -> Vec<OverlayAction> {
        let mut actions = Vec::new();
        if !self.visible {
            return actions;
        }
        // At most half the window's width and half its height, a quarter of it, however
        // many passes and variants it lists (the rest scrolls); the title bar collapses it.
        let screen = ctx.content_rect().size();
        egui::Window::new("lightgraph")
            .default_pos([8.0, 8.0])
            .default_width(300.0f32.min(screen.x * 0.5))
            .max_width(screen.x * 0.5)
            .max_height(screen.y * 0.5)
            .vscroll(true)
            .collapsible(true)
            .show(ctx, |ui| {
                ui.label(format!(
                    "{} · {} lights · {}×{}",
                    info.scene, info.lights, info.render_size[0], info.render_size[1]
                ));
                ui.label(format!("{} · {:.1} ms/frame", info.adapter, info.frame_ms));
                if let Some(e) = &info.error {
                    ui.separator();
                    ui.colored_label(
                        egui::Color32::from_rgb(255, 110, 110),
                        "Reload failed; the last good version keeps rendering:",
                    );
                    ui.monospace(e);
                } else if let Some(r) = &info.last_reload {
                    ui.label(format!("reloaded: {r}"));
                }
                egui::CollapsingHeader::new("GPU times and light statistics")
                    .default_open(true)
                    .show(ui, |ui| {
                        self.pass_times(ui, info);
                        self.light_statistics(ui, info);
                    });
                egui::CollapsingHeader::new("graph variant, camera, exposure")
                    .default_open(true)
                    .show(ui, |ui| self.controls(ui, &mut actions));
                ui.small(
                    "drag: rotate · wheel: zoom/speed · WASD QE: move · Tab: mode · Space: pause lights · F1: overlay",
                );
            });
        actions
    }

    fn pass_times(&self, ui: &mut egui::Ui, info: &FrameInfo) {
        match &info.pass_ms {
            Some(passes) => {
                egui::Grid::new("passes").striped(true).show(ui, |ui| {
                    for (name, ms) in passes {
                        ui.label(name);
                        ui.monospace(format!("{ms:8.3} ms"));
                        ui.end_row();
                    }
                    ui.strong("GPU total");
                    let total: f64 = passes.iter().map(|p| p.1).sum();
                    ui.monospace(format!("{total:8.3} ms"));
                    ui.end_row();
                });
            }
            None => {
                ui.label("this adapter has no timestamp queries: no per-pass GPU times");
            }
        }
    }

    fn light_statistics(&self, ui: &mut egui::Ui, info: &FrameInfo) {
        for c in &info.culling {
            ui.label(c.summary());
            for w in c.warnings() {
                ui.colored_label(egui::Color32::YELLOW, w);
            }
        }
        if let Some(s) = &info.light_stats {
            ui.label(format!(
                "lights per pixel: listed {:.2}, reaching {:.2} (listed/exact {:.2}); max listed {}",
                s.avg_listed(),
                s.avg_exact(),
                s.false_positive_ratio(),
                s.max_listed
            ));
        }
    }

    fn controls(&mut self, ui: &mut egui::Ui, actions: &mut Vec<OverlayAction>) {
        ui.label("graph variant");
        for g in &self.graphs {
            if ui.radio(*g == self.current_graph, graph_label(g)).clicked()
                && *g != self.current_graph
            {
                actions.push(OverlayAction::SelectGraph(g.clone()));
            }
        }
        ui.horizontal(|ui| {
            ui.label("camera");
            for (mode, label) in [(CameraMode::Orbit, "orbit"), (CameraMode::Fly, "fly")] {
                if ui.radio(self.camera_mode == mode, label).clicked() && self.camera_mode != mode {
                    self.camera_mode = mode;
                    actions.push(OverlayAction::CameraMode(mode));
                }
            }
        });
        ui.add(egui::Slider::new(&mut self.exposure_ev, -10.0..=10.0).text("exposure (EV)"));
        if ui
            .checkbox(
                &mut self.light_stats,
                "lights per pixel (adds a brute-force pass)",
            )
            .changed()
        {
            actions.push(OverlayAction::LightStats(self.light_stats));
        }
    }
}
