//! A Markov chain's state: its primary sample vector in three streams, mutated by small
//! normal steps or drawn afresh by large steps (pbrt-v3's `MLTSampler`).

use crate::math::{PI, Vec2};
use crate::sampling::Samples;
use crate::stats::Pcg32;

/// Streams of a state's numbers: camera subpath, light subpath, connections.
const STREAMS: usize = 3;

#[derive(Clone, Copy, Default)]
pub(super) struct PrimarySample {
    /// Drawn at all: a number no state has used yet is a fresh uniform one (the target
    /// density does not depend on it).
    drawn: bool,
    value: f32,
    modified: u64,
    backup: f32,
    backup_modified: u64,
}

/// A Markov chain's primary sample vector (pbrt-v3's `MLTSampler`).
pub(super) struct MltSampler {
    rng: Pcg32,
    sigma: f32,
    large_step_p: f32,
    x: Vec<PrimarySample>,
    iteration: u64,
    pub(super) large_step: bool,
    last_large_step: u64,
    stream: usize,
    index: usize,
}

impl MltSampler {
    pub(super) fn new(seed: u64, sigma: f32, large_step_p: f32) -> MltSampler {
        MltSampler {
            rng: Pcg32::new(seed, 0x4D4C_545F),
            sigma,
            large_step_p,
            x: Vec::new(),
            iteration: 0,
            // The first state is drawn afresh.
            large_step: true,
            last_large_step: 0,
            stream: 0,
            index: 0,
        }
    }

    pub(super) fn start_iteration(&mut self) {
        self.iteration += 1;
        self.large_step = self.rng.next_f32() < self.large_step_p;
    }

    pub(super) fn accept(&mut self) {
        if self.large_step {
            self.last_large_step = self.iteration;
        }
    }

    pub(super) fn reject(&mut self) {
        for x in &mut self.x {
            if x.modified == self.iteration {
                x.value = x.backup;
                x.modified = x.backup_modified;
            }
        }
        self.iteration -= 1;
    }

    /// A standard normal number (Box–Muller).
    fn normal(&mut self) -> f32 {
        let u1 = 1.0 - self.rng.next_f32();
        let u2 = self.rng.next_f32();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }

    fn next(&mut self) -> f32 {
        let i = self.stream + STREAMS * self.index;
        self.index += 1;
        if i >= self.x.len() {
            self.x.resize(i + 1, PrimarySample::default());
        }
        if !self.x[i].drawn {
            let v = self.rng.next_f32();
            self.x[i] = PrimarySample {
                drawn: true,
                value: v,
                modified: self.iteration,
                backup: v,
                backup_modified: self.iteration,
            };
            return v;
        }
        // Bring the number up to date: a fresh draw if it missed the last large step, then
        // the small steps since (one normal step of the combined deviation).
        if self.x[i].modified < self.last_large_step {
            let v = self.rng.next_f32();
            self.x[i].value = v;
            self.x[i].modified = self.last_large_step;
        }
        let x = self.x[i];
        self.x[i].backup = x.value;
        self.x[i].backup_modified = x.modified;
        let value = if self.large_step {
            self.rng.next_f32()
        } else {
            let steps = (self.iteration - x.modified) as f32;
            let v = x.value + self.normal() * self.sigma * steps.sqrt();
            let v = v - v.floor();
            if v < 1.0 { v } else { 0.0 }
        };
        self.x[i].value = value;
        self.x[i].modified = self.iteration;
        value
    }
}

impl Samples for MltSampler {
    fn next_1d(&mut self) -> f32 {
        self.next()
    }
    fn next_2d(&mut self) -> Vec2 {
        let a = self.next();
        Vec2::new(a, self.next())
    }
    fn start_stream(&mut self, stream: usize) {
        self.stream = stream;
        self.index = 0;
    }
}
