//! The live reference: the path tracer accumulating the current view at the window's size, a
//! few samples per frame under a share of the frame time, restarted when the view, the scene's
//! animation or the kind of reference changes; and the method's error against it, computed on
//! a worker thread so that the frame that completes a sample does not wait for the metrics.

use std::sync::mpsc::{channel, Receiver, Sender, TryRecvError};
use std::thread::JoinHandle;
use std::time::Instant;

use crate::backend::{Gpu, GpuDesc};
use crate::commands::chart::{reference_noise, reference_settings};
use crate::error::Result;
use crate::lighting::ReferenceKind;
use crate::metrics::{compare, CompareOptions};
use crate::reference::{ReferenceImage, ReferenceRenderer, Sampler, Settings};
use crate::scene::{Camera, Scene};
use crate::util::image_io::HdrImage;

/// The most samples one frame's batch adds (the tracer's batches are capped the same way).
const MAX_FRAME_BATCH: u32 = 64;

/// What the reference must match to keep accumulating.
#[derive(Clone, Debug, PartialEq)]
struct Traced {
    camera: Camera,
    kind: ReferenceKind,
    size: (u32, u32),
    /// The animation frame traced; `None` when nothing in the scene moves.
    frame: Option<u64>,
}

/// The method's error against the reference so far, and the reference's own.
#[derive(Clone, Debug, serde::Serialize)]
pub struct LiveError {
    pub rel_mse: f64,
    pub flip: f64,
    pub mean_ratio: f64,
    /// What an exact image would score against this reference (`chart`'s noise level).
    pub noise_rel_mse: f64,
    pub noise_flip: f64,
    pub spp: u32,
}

pub struct LiveReference {
    desc: GpuDesc,
    tracer: Option<ReferenceRenderer>,
    traced: Option<Traced>,
    settings: Settings,
    pub label: String,
    pub image: Option<ReferenceImage>,
    /// The share of the frame time the reference (tracing, read-back and metrics) may take.
    pub budget: f32,
    /// Seconds of reference work earned and not yet spent.
    credit: f64,
    /// Seconds per sample of one pixel, smoothed; `None` until the first timed batch.
    per_pixel_sample: Option<f64>,
    /// The sample in progress band by band (where one sample of the image costs more than a
    /// frame's share): the next row to trace.
    band: u32,
    /// The frame time without the reference's work, smoothed.
    other: Option<f64>,
    pub restarts: u32,
    /// The tracer was just made: its first batch also compiles its pipeline.
    compiling: bool,
    /// The error of the configuration last measured, refreshed by [`LiveReference::measure`]
    /// or, off the frame, by [`LiveReference::measure_in_background`].
    pub error: Option<LiveError>,
    /// Changes with what an error refers to (a restart, another method): results of the worker
    /// for an earlier epoch are dropped.
    epoch: u64,
    worker: MetricsWorker,
}

/// A measurement for the worker: the method's image against the reference's, both as they were.
struct Job {
    epoch: u64,
    method: HdrImage,
    reference: ReferenceImage,
    exposure: f32,
}

struct Done {
    epoch: u64,
    result: std::result::Result<LiveError, String>,
    seconds: f64,
}

/// A thread computing the error metrics, one measurement at a time.
struct MetricsWorker {
    jobs: Option<Sender<Job>>,
    results: Receiver<Done>,
    thread: Option<JoinHandle<()>>,
    busy: bool,
}

impl MetricsWorker {
    fn new() -> MetricsWorker {
        let (jobs, inbox) = channel::<Job>();
        let (outbox, results) = channel();
        let thread = std::thread::spawn(move || {
            for job in inbox {
                let start = Instant::now();
                let result = evaluate(&job.method, &job.reference, job.exposure).map_err(|e| e.to_string());
                let done = Done {
                    epoch: job.epoch,
                    result,
                    seconds: start.elapsed().as_secs_f64(),
                };
                if outbox.send(done).is_err() {
                    break;
                }
            }
        });
        MetricsWorker {
            jobs: Some(jobs),
            results,
            thread: Some(thread),
            busy: false,
        }
    }
}

impl Drop for MetricsWorker {
    fn drop(&mut self) {
        // Closing the queue ends the thread after the measurement in hand.
        self.jobs = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The method's error against a reference image and the reference's own noise level: what
/// `penumbra compare` and `penumbra chart` compute.
fn evaluate(method: &HdrImage, reference: &ReferenceImage, exposure: f32) -> Result<LiveError> {
    let opts = CompareOptions {
        exposure,
        ..CompareOptions::default()
    };
    let m = compare(method, &reference.mean, &opts).map_err(|e| crate::Error::Usage(e.to_string()))?;
    let noise = reference_noise(reference)?;
    Ok(LiveError {
        rel_mse: m.rel_mse,
        flip: m.flip_mean,
        mean_ratio: m.mean_ratio,
        noise_rel_mse: noise.rel_mse,
        noise_flip: noise.flip_mean,
        spp: reference.spp,
    })
}

impl LiveReference {
    pub fn new(desc: GpuDesc, budget: f32) -> LiveReference {
        let (settings, label) = reference_settings(ReferenceKind::Direct, u32::MAX, Sampler::Independent);
        LiveReference {
            desc,
            tracer: None,
            traced: None,
            settings,
            label,
            image: None,
            budget,
            credit: 0.0,
            per_pixel_sample: None,
            band: 0,
            other: None,
            restarts: 0,
            compiling: false,
            error: None,
            epoch: 0,
            worker: MetricsWorker::new(),
        }
    }

    pub fn spp(&self) -> u32 {
        self.image.as_ref().map_or(0, |i| i.spp)
    }

    /// Starts over when what the image shows changed: the camera, the kind of reference, the
    /// size, or (in a scene that moves) the animation frame. The tracer is rebuilt for a new
    /// size or frame; a new view only moves its camera.
    pub fn follow(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        kind: ReferenceKind,
        size: (u32, u32),
        frame: u64,
    ) -> Result<()> {
        let frame = scene.motion_summary().map(|_| frame);
        let want = Traced {
            camera: camera.clone(),
            kind,
            size,
            frame,
        };
        if self.traced.as_ref() == Some(&want) {
            return Ok(());
        }
        let rebuild = match &self.traced {
            Some(t) => t.size != size || t.frame != frame,
            None => true,
        };
        if rebuild || self.tracer.is_none() {
            self.tracer = None;
            let gpu = Gpu::new(&self.desc)?;
            self.tracer = Some(ReferenceRenderer::at_frame(gpu, scene, size, frame.unwrap_or(0))?);
            self.compiling = true;
        }
        if let Some(t) = self.tracer.as_mut() {
            t.set_camera(camera);
        }
        let (settings, label) = reference_settings(kind, u32::MAX, Sampler::Independent);
        self.settings = settings;
        self.label = label;
        self.traced = Some(want);
        self.image = None;
        self.error = None;
        self.epoch += 1;
        self.credit = 0.0;
        self.band = 0;
        self.restarts += 1;
        Ok(())
    }

    /// Tells the reference how long the frame took without its work, and earns it its share.
    pub fn frame_time(&mut self, seconds_without_reference: f64) {
        let s = seconds_without_reference.max(1e-4);
        self.other = Some(self.other.map_or(s, |o| 0.8 * o + 0.2 * s));
        let b = self.budget.clamp(0.0, 0.95) as f64;
        let earned = self.other.unwrap_or(s) * b / (1.0 - b);
        // Credit does not pile up while nothing can be spent (a still camera is needed).
        self.credit = (self.credit + earned).min(earned * 4.0);
    }

    /// Adds the samples the credit pays for and reads the image back when a sample of every
    /// pixel is complete. Where a sample of the whole image costs more than the credit, it is
    /// traced in bands of rows over several frames. Returns whether the image grew.
    pub fn step(&mut self) -> Result<bool> {
        if self.budget <= 0.0 {
            return Ok(false);
        }
        let Some(tracer) = self.tracer.as_mut() else {
            return Ok(false);
        };
        let (width, height) = self.traced.as_ref().map_or((1, 1), |t| t.size);
        let done = self.image.as_ref().map_or(0, |i| i.spp);
        // The first batch of a new tracer also compiles it: a whole sample, whatever it costs.
        let (mut count, rows) = match self.per_pixel_sample {
            _ if self.compiling => (1, 0..height),
            None => (1, 0..height),
            Some(p) => {
                let row = p * width as f64;
                let image = row * height as f64;
                if self.band == 0 && self.credit >= image {
                    (((self.credit / image) as u32).clamp(1, MAX_FRAME_BATCH), 0..height)
                } else if self.credit >= row {
                    let rows = ((self.credit / row) as u32).clamp(1, height - self.band);
                    (1, self.band..self.band + rows)
                } else {
                    return Ok(false);
                }
            }
        };
        let last_band = rows.end == height;
        let start = Instant::now();
        let image = loop {
            match tracer.accumulate(&self.settings, (done, count), rows.clone(), last_band)? {
                Some(image) => break Some(image),
                None if !last_band => break None,
                // Cut short by the device: the same batch, halved.
                None => count = (count / 2).max(1),
            }
        };
        let took = start.elapsed().as_secs_f64();
        // The compile is a one-off cost of the tracer (and of the size: a new tracer), not
        // charged to the frames' budget nor to the cost of a sample.
        if std::mem::take(&mut self.compiling) {
            self.credit = 0.0;
        } else {
            let p = took / (count as f64 * (rows.end - rows.start) as f64 * width as f64);
            self.per_pixel_sample = Some(self.per_pixel_sample.map_or(p, |q| 0.7 * q + 0.3 * p));
            self.spend(took);
        }
        self.band = if last_band { 0 } else { rows.end };
        match image {
            Some(image) => {
                self.image = Some(image);
                Ok(true)
            }
            None => Ok(false),
        }
    }

    /// Charges reference work done outside [`LiveReference::step`] (the metrics).
    pub fn spend(&mut self, seconds: f64) {
        self.credit -= seconds;
    }

    /// The method's error against the reference so far (and the reference's own noise level),
    /// now: for a switch of method, whose numbers change within the frame. A measurement of the
    /// previous method still on the worker is dropped.
    pub fn measure(&mut self, method: &HdrImage, exposure: f32) -> Result<Option<&LiveError>> {
        self.epoch += 1;
        let Some(image) = self.image.as_ref().filter(|i| same_size(method, i)) else {
            return Ok(None);
        };
        self.error = Some(evaluate(method, image, exposure)?);
        Ok(self.error.as_ref())
    }

    /// Hands the measurement of `method` against the reference so far to the worker (its result
    /// comes through [`LiveReference::take_measurement`]); false when the worker is busy.
    pub fn measure_in_background(&mut self, method: &HdrImage, exposure: f32) -> bool {
        let (Some(image), Some(jobs)) = (self.image.as_ref(), self.worker.jobs.as_ref()) else {
            return false;
        };
        if self.worker.busy || !same_size(method, image) {
            return false;
        }
        let job = Job {
            epoch: self.epoch,
            method: method.clone(),
            reference: image.clone(),
            exposure,
        };
        self.worker.busy = jobs.send(job).is_ok();
        self.worker.busy
    }

    /// A measurement is on the worker.
    pub fn measuring(&self) -> bool {
        self.worker.busy
    }

    /// The worker's result, once it has one: what the measurement cost it (seconds). A result
    /// for an image since replaced by a restart or a switch of method is dropped.
    pub fn take_measurement(&mut self) -> Result<Option<f64>> {
        let done = match self.worker.results.try_recv() {
            Ok(done) => done,
            Err(TryRecvError::Empty) => return Ok(None),
            Err(TryRecvError::Disconnected) => {
                self.worker.busy = false;
                return Err(crate::Error::Internal("the metrics thread has stopped".into()));
            }
        };
        self.worker.busy = false;
        if done.epoch == self.epoch {
            self.error = Some(done.result.map_err(crate::Error::Usage)?);
        }
        Ok(Some(done.seconds))
    }

    /// The device's validation messages, for the demo's final check.
    pub fn validation_messages(&self) -> usize {
        self.tracer.as_ref().map_or(0, |t| t.gpu.validation_log().count())
    }
}

fn same_size(method: &HdrImage, reference: &ReferenceImage) -> bool {
    (method.width, method.height) == (reference.mean.width, reference.mean.height)
}
