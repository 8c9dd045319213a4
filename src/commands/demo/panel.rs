//! The demo's on-screen panel (egui): what the frame is drawn with and what it costs, the live
//! reference and the error against it, the view, the camera. It changes only the settings it is
//! given; what needs the renderer comes back as [`Action`]s.

use std::collections::VecDeque;

use crate::backend::PassTiming;
use crate::commands::views::{ErrorMap, View, ViewSettings};
use crate::lighting::Configuration;
use crate::scene::ParamKind;

use super::live::LiveReference;
use super::rebake::BakeStatus;

/// A method parameter as edited: TOML text, applied with the Apply button.
#[derive(Clone, Debug)]
pub struct ParamEdit {
    pub part: usize,
    pub name: &'static str,
    pub kind: ParamKind,
    pub text: String,
}

/// What the panel asks of the demo.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    Configuration(usize),
    ApplyParams,
    /// Stop the background bake.
    CancelBake,
    ReloadShaders,
    Screenshot,
    AddBookmark,
    GoToBookmark(usize),
}

/// What the panel shows and does not change.
pub struct PanelInfo<'a> {
    pub configurations: &'a [Configuration],
    pub current: usize,
    /// The configuration the frame is drawn with: the current one, or a stand-in drawing while
    /// the current one bakes at start-up.
    pub drawn: &'a str,
    pub timings: &'a [PassTiming],
    /// Recent frame intervals (ms), oldest first.
    pub frame_ms: &'a VecDeque<f32>,
    /// Recent frames' GPU time (ms, from the timestamp queries), oldest first.
    pub gpu_ms: &'a VecDeque<f32>,
    pub live: &'a LiveReference,
    pub position: glam::Vec3,
    pub bookmarks: usize,
    pub messages: &'a [String],
    /// The bake of the configuration being switched to, running beside the frames.
    pub baking: Option<&'a BakeStatus>,
    /// The configuration asked for while it runs.
    pub queued: Option<&'a str>,
    /// How the last bake that did not switch ended (cancelled).
    pub bake_note: Option<&'a str>,
}

/// What the panel changes.
pub struct PanelSettings<'a> {
    pub view: &'a mut ViewSettings,
    pub speed: &'a mut f32,
    pub budget: &'a mut f32,
    pub live_on: &'a mut bool,
    /// The scene's animation stands still (the reference accumulates).
    pub paused: &'a mut bool,
    pub params: &'a mut Vec<ParamEdit>,
}

/// Draws the panel; returns what it asks for.
pub fn draw(ctx: &egui::Context, info: &PanelInfo<'_>, settings: PanelSettings<'_>) -> Vec<Action> {
    let mut actions = Vec::new();
    egui::Window::new("penumbra")
        .default_pos([8.0, 8.0])
        .default_width(260.0)
        .resizable(true)
        .show(ctx, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                if let Some(b) = info.baking {
                    baking(ui, b, info.drawn, info.queued, &mut actions);
                } else if let Some(note) = info.bake_note {
                    ui.colored_label(egui::Color32::from_rgb(230, 200, 90), note);
                }
                configuration(ui, info, settings.params, &mut actions);
                timings(ui, info);
                reference(ui, info, settings.budget, settings.live_on, settings.paused);
                view(ui, settings.view, &mut actions);
                camera(ui, info, settings.speed, &mut actions);
                for m in info.messages {
                    ui.colored_label(egui::Color32::from_rgb(255, 120, 100), m);
                }
            });
        });
    actions
}

/// The background bake: its stage's progress bar, the time so far and the stage's estimate, and
/// the button that cancels it.
fn baking(ui: &mut egui::Ui, b: &BakeStatus, drawn: &str, queued: Option<&str>, actions: &mut Vec<Action>) {
    ui.label(format!("baking {} ({:.1} s)", b.configuration, b.elapsed_s));
    let left = b.left_s.map_or(String::new(), |s| format!(", about {s:.0} s left"));
    ui.add(egui::ProgressBar::new(b.fraction as f32).text(format!("{} {:.0}%{left}", b.stage, 100.0 * b.fraction)));
    match queued {
        Some(q) => ui.label(format!("then {q}; {drawn} draws meanwhile")),
        None => ui.label(format!("{drawn} draws meanwhile")),
    };
    if b.cancelling {
        ui.label("cancelling...");
    } else if ui.button("Cancel bake (C)").clicked() {
        actions.push(Action::CancelBake);
    }
}

/// What the method box says is drawn: the current configuration, or the stand-in drawing while
/// the current one bakes (at start-up, before anything of it is in the bake cache) and how far
/// that bake has come.
pub fn method_label(current: Option<&str>, drawn: &str, baking: Option<&BakeStatus>) -> String {
    match baking {
        _ if current == Some(drawn) => drawn.to_string(),
        Some(b) => format!("{drawn} — baking {} {:.0} %", b.configuration, 100.0 * b.fraction),
        None => drawn.to_string(),
    }
}

fn configuration(ui: &mut egui::Ui, info: &PanelInfo<'_>, params: &mut [ParamEdit], actions: &mut Vec<Action>) {
    ui.collapsing("Configuration", |ui| {
        let names: Vec<&str> = info.configurations.iter().map(|c| c.name.as_str()).collect();
        let mut chosen = info.current;
        egui::ComboBox::from_label("method (M)")
            .selected_text(method_label(names.get(info.current).copied(), info.drawn, info.baking))
            .show_ui(ui, |ui| {
                for (i, n) in names.iter().enumerate() {
                    ui.selectable_value(&mut chosen, i, *n);
                }
            });
        if chosen != info.current {
            actions.push(Action::Configuration(chosen));
        }
        let parts: Vec<&str> = info
            .configurations
            .get(info.current)
            .map(|c| c.parts.iter().map(|p| p.decl.name.as_str()).collect())
            .unwrap_or_default();
        egui::Grid::new("params").num_columns(2).show(ui, |ui| {
            for p in params.iter_mut() {
                ui.label(format!("{}.{}", parts.get(p.part).copied().unwrap_or("?"), p.name));
                if p.name == "mode" {
                    egui::ComboBox::from_id_salt(("mode", p.part))
                        .selected_text(if p.text.is_empty() {
                            "(default)"
                        } else {
                            p.text.as_str()
                        })
                        .show_ui(ui, |ui| {
                            for m in ["\"faithful\"", "\"corrected\""] {
                                ui.selectable_value(&mut p.text, m.to_string(), m);
                            }
                        });
                } else {
                    ui.add(egui::TextEdit::singleline(&mut p.text).hint_text(p.kind.to_string()));
                }
                ui.end_row();
            }
        });
        ui.horizontal(|ui| {
            if ui.button("Apply (rebake)").clicked() {
                actions.push(Action::ApplyParams);
            }
            if ui.button("Reload shaders (R)").clicked() {
                actions.push(Action::ReloadShaders);
            }
        });
    });
}

fn timings(ui: &mut egui::Ui, info: &PanelInfo<'_>) {
    ui.collapsing("GPU passes", |ui| {
        egui::Grid::new("timings").num_columns(2).striped(true).show(ui, |ui| {
            for t in info.timings {
                ui.label(&t.name);
                ui.label(format!("{:.3} ms", t.ms));
                ui.end_row();
            }
        });
        let last = info.frame_ms.back().copied().unwrap_or(0.0);
        let gpu = info.gpu_ms.back().copied().unwrap_or(0.0);
        ui.label(format!(
            "GPU {gpu:.2} ms, frame {last:.1} ms ({:.1} fps)",
            1000.0 / last.max(1e-3)
        ));
        frame_graph(ui, info.gpu_ms, info.frame_ms);
    })
    .header_response
    .on_hover_text("GPU time per pass from timestamp queries; graph: GPU time (orange), frame interval (green)");
}

/// The frames' GPU times and intervals as two lines, scaled to the largest of either.
fn frame_graph(ui: &mut egui::Ui, gpu: &VecDeque<f32>, frame: &VecDeque<f32>) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width().max(100.0), 48.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, egui::Color32::from_gray(20));
    let top = gpu.iter().chain(frame).copied().fold(1.0f32, f32::max);
    for (ms, colour) in [(frame, egui::Color32::LIGHT_GREEN), (gpu, egui::Color32::ORANGE)] {
        let n = ms.len().max(2) as f32;
        let points: Vec<egui::Pos2> = ms
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                egui::pos2(
                    rect.left() + rect.width() * i as f32 / (n - 1.0),
                    rect.bottom() - rect.height() * v / top,
                )
            })
            .collect();
        painter.add(egui::Shape::line(points, egui::Stroke::new(1.0, colour)));
    }
    painter.text(
        rect.left_top(),
        egui::Align2::LEFT_TOP,
        format!("{top:.0} ms"),
        egui::FontId::monospace(10.0),
        egui::Color32::GRAY,
    );
}

fn reference(ui: &mut egui::Ui, info: &PanelInfo<'_>, budget: &mut f32, live_on: &mut bool, paused: &mut bool) {
    ui.collapsing("Reference and error", |ui| {
        ui.checkbox(live_on, "live reference (G)");
        ui.checkbox(paused, "pause animation (P)")
            .on_hover_text("in a scene that moves the reference restarts every frame; paused, it accumulates");
        ui.add(egui::Slider::new(budget, 0.05..=0.9).text("share of frame"));
        let live = info.live;
        ui.label(format!("{}: {} spp", live.label, live.spp()));
        match &live.error {
            Some(e) => {
                if e.spp != live.spp() {
                    ui.label(format!("error at {} spp (being refreshed)", e.spp));
                }
                egui::Grid::new("error").num_columns(3).show(ui, |ui| {
                    ui.label("");
                    ui.label("method");
                    ui.label("ref. noise");
                    ui.end_row();
                    ui.label("relative MSE");
                    ui.label(format!("{:.4e}", e.rel_mse));
                    ui.label(format!("{:.2e}", e.noise_rel_mse));
                    ui.end_row();
                    ui.label("FLIP");
                    ui.label(format!("{:.4}", e.flip));
                    ui.label(format!("{:.4}", e.noise_flip));
                    ui.end_row();
                    ui.label("mean ratio");
                    ui.label(format!("{:.4}", e.mean_ratio));
                    ui.end_row();
                });
                if e.noise_rel_mse > 0.1 * e.rel_mse {
                    ui.label("(the reference's noise is still a large part of the error)");
                }
            }
            None => {
                ui.label("no error yet (waiting for samples)");
            }
        }
    });
}

fn view(ui: &mut egui::Ui, v: &mut ViewSettings, actions: &mut Vec<Action>) {
    ui.collapsing("View", |ui| {
        ui.horizontal_wrapped(|ui| {
            for (i, candidate) in View::ALL.into_iter().enumerate() {
                ui.selectable_value(&mut v.view, candidate, format!("{} {}", i + 1, candidate.name()));
            }
        });
        ui.add(
            egui::Slider::new(&mut v.exposure, 0.05..=16.0)
                .logarithmic(true)
                .text("exposure (+/-)"),
        );
        if v.view == View::Split {
            ui.add(egui::Slider::new(&mut v.split, 0.0..=1.0).text("divider"));
        }
        if matches!(v.view, View::Error | View::Difference) {
            ui.horizontal(|ui| {
                ui.selectable_value(&mut v.error_map, ErrorMap::Relative, "relative (X)");
                ui.selectable_value(&mut v.error_map, ErrorMap::Flip, "FLIP");
            });
            ui.add(
                egui::Slider::new(&mut v.scale, 0.01..=4.0)
                    .logarithmic(true)
                    .text("scale top"),
            );
            if v.view == View::Error {
                ui.label(format!("colour bar at the bottom: 0 (left) to {:.2} (right)", v.scale));
            }
        }
        if ui.button("Screenshot PNG + EXR (F12)").clicked() {
            actions.push(Action::Screenshot);
        }
    });
}

fn camera(ui: &mut egui::Ui, info: &PanelInfo<'_>, speed: &mut f32, actions: &mut Vec<Action>) {
    ui.collapsing("Camera", |ui| {
        let p = info.position;
        ui.label(format!("position {:.2} {:.2} {:.2}", p.x, p.y, p.z));
        ui.add(egui::Slider::new(speed, 0.1..=50.0).logarithmic(true).text("speed m/s"));
        ui.horizontal_wrapped(|ui| {
            if ui.button("Bookmark (B)").clicked() {
                actions.push(Action::AddBookmark);
            }
            for i in 0..info.bookmarks {
                if ui.button(format!("{}", i + 1)).clicked() {
                    actions.push(Action::GoToBookmark(i));
                }
            }
        });
    });
}
