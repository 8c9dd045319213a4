//! A configuration's bakes run on a thread of their own while the window goes on drawing the
//! old configuration: the thread creates the configuration's methods on a device of its own (a
//! token-sized renderer, as `penumbra bake` does), which fills the bake cache, and reports each
//! bake's progress through a channel. Once it is done the demo switches, reading the bakes back
//! from the cache. It can be cancelled: the bakes look at the cancellation between batches, stop,
//! and cache nothing.

use std::sync::mpsc::{channel, Receiver, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use crate::backend::{Gpu, GpuDesc};
use crate::bake::Baker;
use crate::error::{Error, Result};
use crate::lighting::Configuration;
use crate::renderer::Renderer;
use crate::scene::Scene;
use crate::util::progress::{cancel_this_thread, observe_this_thread, Cancel, Update};

/// What the panel shows of a bake in progress (and the report records).
#[derive(Clone, Debug, serde::Serialize)]
pub struct BakeStatus {
    pub configuration: String,
    /// The bake running now (`starting` until the first one begins).
    pub stage: String,
    /// Of the stage, in [0, 1].
    pub fraction: f64,
    /// Since the rebake started.
    pub elapsed_s: f64,
    /// What the stage has left at its rate so far; `None` until it has a rate.
    pub left_s: Option<f64>,
    /// Cancelled, and not yet stopped.
    pub cancelling: bool,
}

enum Message {
    Progress(Update),
    Done(Outcome),
}

/// How a finished rebake went.
pub enum Outcome {
    /// The bakes' names, whether each came from the cache, and the device's validation messages.
    Baked {
        bakes: Vec<(String, bool)>,
        validation_messages: usize,
    },
    /// Stopped when asked to, at the bake named; nothing of it was cached.
    Cancelled(String),
    Failed(String),
}

pub struct Rebake {
    /// The configuration's index in the demo's list and the configuration itself.
    pub index: usize,
    pub configuration: Configuration,
    pub status: BakeStatus,
    started: Instant,
    messages: Receiver<Message>,
    thread: Option<JoinHandle<()>>,
    cancel: Cancel,
}

impl Rebake {
    /// Starts `configuration`'s bakes on a new thread with a device made from `desc`.
    pub fn start(desc: &GpuDesc, scene: Scene, index: usize, configuration: Configuration) -> Rebake {
        let (tx, rx) = channel();
        let config = configuration.clone();
        // A description without the window's display (which may not cross threads): the bake
        // presents nothing.
        let (validation, device_name) = (desc.validation, desc.device_name.clone());
        let cancel = Cancel::new();
        let cancel_here = cancel.clone();
        let thread = std::thread::spawn(move || {
            let desc = GpuDesc {
                validation,
                device_name,
                display: None,
            };
            let progress = tx.clone();
            observe_this_thread(Some(Arc::new(move |u: &Update| {
                // The demo may have gone (the window closed): nobody left to tell.
                let _ = progress.send(Message::Progress(u.clone()));
            })));
            cancel_this_thread(Some(cancel_here));
            let outcome = match bake(&desc, scene, config) {
                Ok((bakes, validation_messages)) => Outcome::Baked {
                    bakes,
                    validation_messages,
                },
                Err(Error::Cancelled(at)) => Outcome::Cancelled(at),
                Err(e) => Outcome::Failed(e.to_string()),
            };
            cancel_this_thread(None);
            observe_this_thread(None);
            let _ = tx.send(Message::Done(outcome));
        });
        Rebake {
            index,
            status: BakeStatus {
                configuration: configuration.name.clone(),
                stage: "starting".into(),
                fraction: 0.0,
                elapsed_s: 0.0,
                left_s: None,
                cancelling: false,
            },
            configuration,
            started: Instant::now(),
            messages: rx,
            thread: Some(thread),
            cancel,
        }
    }

    /// Asks the bakes to stop; [`Rebake::poll`] reports [`Outcome::Cancelled`] once they have.
    pub fn cancel(&mut self) {
        self.cancel.cancel();
        self.status.cancelling = true;
    }

    /// Takes the thread's messages into the status; returns the outcome once it has finished.
    pub fn poll(&mut self) -> Option<Outcome> {
        self.status.elapsed_s = self.started.elapsed().as_secs_f64();
        loop {
            match self.messages.try_recv() {
                Ok(Message::Progress(u)) => {
                    let fraction = if u.total > 0 {
                        (u.done as f64 / u.total as f64).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let secs = u.elapsed.as_secs_f64();
                    self.status.stage = u.name;
                    self.status.fraction = fraction;
                    self.status.left_s = (fraction > 0.0).then(|| secs * (1.0 - fraction) / fraction);
                }
                Ok(Message::Done(outcome)) => {
                    self.join();
                    return Some(outcome);
                }
                Err(TryRecvError::Empty) => return None,
                Err(TryRecvError::Disconnected) => {
                    self.join();
                    return Some(Outcome::Failed("the bake thread ended without a result".into()));
                }
            }
        }
    }

    /// Waits for the thread to finish (the window is closing) and returns how it went.
    pub fn wait(self) -> Outcome {
        if self.thread.as_ref().is_some_and(|t| !t.is_finished()) {
            crate::outln!("waiting for the bake of {} to finish", self.configuration.name);
        }
        loop {
            match self.messages.recv() {
                Ok(Message::Progress(_)) => continue,
                Ok(Message::Done(outcome)) => return outcome,
                Err(_) => return Outcome::Failed("the bake thread ended without a result".into()),
            }
        }
    }

    fn join(&mut self) {
        if let Some(t) = self.thread.take() {
            // A panic in the thread was already printed, and its disconnect reported.
            let _ = t.join();
        }
    }
}

impl Drop for Rebake {
    /// The window closing waits for the bake's thread (cancelled first, so it ends soon): its
    /// device must go before the process ends.
    fn drop(&mut self) {
        self.join();
    }
}

/// Creates the configuration's methods at a token size, which runs their bakes into the cache. A
/// bake that could not be stored there fails the rebake: the switch would otherwise bake it again,
/// in the frame.
fn bake(desc: &GpuDesc, scene: Scene, configuration: Configuration) -> Result<(Vec<(String, bool)>, usize)> {
    let renderer = Renderer::with_configuration(
        Gpu::new(desc)?,
        scene,
        configuration,
        (1, 1),
        1,
        Baker::new(Some(Baker::default_dir())),
    )?;
    if let Some((name, why)) = renderer
        .bakes
        .iter()
        .find_map(|b| b.not_stored.as_ref().map(|why| (&b.name, why)))
    {
        return Err(Error::Usage(format!("{name} was baked but cannot be cached: {why}")));
    }
    let bakes = renderer.bakes.iter().map(|b| (b.name.clone(), b.cached)).collect();
    let validation = renderer.gpu.validation_log().count();
    Ok((bakes, validation))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bake that cannot run (here: no device of that name) ends as a failure with its reason,
    /// which the demo shows in the panel while the old configuration keeps drawing.
    #[test]
    fn a_bake_that_cannot_run_reports_why() {
        let text = "methods = [\"forward\"]\n[camera]\nposition = [0, 1, 2]\ntarget = [0, 0, 0]\n[[objects]]\nmesh = \"plane\"\nsize = [1, 1]\n";
        let scene = Scene::from_str(text, "test.toml", std::path::Path::new(".")).unwrap();
        let config = crate::lighting::registry::configuration(&scene, None).unwrap();
        let desc = GpuDesc {
            device_name: Some("no device is called this".into()),
            ..GpuDesc::default()
        };
        let mut rebake = Rebake::start(&desc, scene, 0, config);
        let outcome = loop {
            if let Some(o) = rebake.poll() {
                break o;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        };
        match outcome {
            Outcome::Failed(why) => assert!(why.contains("no device is called this"), "{why}"),
            Outcome::Baked { .. } | Outcome::Cancelled(_) => panic!("baked without a device"),
        }
    }
}
