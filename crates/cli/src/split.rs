//! Renders split over processes and time: `--shard I/K` (a range of the render's work
//! items, written as a film state), `--checkpoint`/`--resume`, and `penumbra merge`.
//!
//! The renderer does the exact part (work items, fixed-point film, `render::film::state`);
//! this module names renders (the identity hash of the loaded scene and the options that
//! change the image), picks a shard's items, writes checkpoints from the render's observer
//! and develops merged states.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use render::film::Film;
use render::film::state::{self, FilmState, StateInfo};
use render::image_io::{write_image, write_image_tonemapped};
use render::render::{Progress, RenderObserver};

use crate::Failure;

/// `--shard I/K`: the I-th of K shards (`None`: from the scheduler's environment).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: Option<u32>,
    pub count: u32,
}

/// The environment variables `--shard auto/K` reads, in order: Slurm job arrays,
/// Kubernetes indexed Jobs, anything else.
pub const SHARD_VARIABLES: [&str; 3] = [
    "SLURM_ARRAY_TASK_ID",
    "JOB_COMPLETION_INDEX",
    "PENUMBRA_SHARD",
];

pub fn parse_shard(s: &str) -> Result<Shard, String> {
    let err = || format!("expected I/K (0 ≤ I < K) or auto/K, found '{s}'");
    let (i, k) = s.split_once('/').ok_or_else(err)?;
    let count: u32 = k.trim().parse().map_err(|_| err())?;
    if count == 0 {
        return Err(err());
    }
    let index = match i.trim() {
        "auto" => None,
        i => {
            let i: u32 = i.parse().map_err(|_| err())?;
            if i >= count {
                return Err(err());
            }
            Some(i)
        }
    };
    Ok(Shard { index, count })
}

impl Shard {
    /// The shard's index, from the command line or the scheduler's environment.
    pub fn resolve(&self) -> Result<u32, Failure> {
        let i = match self.index {
            Some(i) => i,
            None => {
                let found = SHARD_VARIABLES
                    .iter()
                    .find_map(|v| std::env::var(v).ok().map(|x| (*v, x)));
                let Some((var, value)) = found else {
                    return Err(Failure::input(format!(
                        "--shard auto/{}: none of {} is set",
                        self.count,
                        SHARD_VARIABLES.join(", ")
                    )));
                };
                value.trim().parse().map_err(|_| {
                    Failure::input(format!("--shard auto: {var}='{value}' is not an index"))
                })?
            }
        };
        if i >= self.count {
            return Err(Failure::input(format!(
                "shard index {i} is not below the shard count {} (indices start at 0)",
                self.count
            )));
        }
        Ok(i)
    }
}

/// Where a render's film state goes: the periodic checkpoint (and how often), and whether
/// to keep the last film in memory for a final state.
pub struct Saver {
    pub identity: u64,
    pub description: String,
    pub items_total: u64,
    pub spp: u32,
    pub tonemap: Option<scene::Tonemap>,
    pub checkpoint: Option<(PathBuf, Duration)>,
    last: Mutex<Option<Instant>>,
    errors: Mutex<Vec<String>>,
}

impl Saver {
    pub fn new(
        identity: u64,
        description: String,
        items_total: u64,
        spp: u32,
        tonemap: Option<scene::Tonemap>,
        checkpoint: Option<(PathBuf, Duration)>,
    ) -> Saver {
        Saver {
            identity,
            description,
            items_total,
            spp,
            tonemap,
            checkpoint,
            last: Mutex::new(Some(Instant::now())),
            errors: Mutex::new(Vec::new()),
        }
    }

    /// Writes the state of `film` with `items` to `path`.
    pub fn write(&self, path: &Path, film: &Film, items: Range<u64>) -> Result<(), Failure> {
        let info = StateInfo {
            identity: self.identity,
            description: self.description.clone(),
            items_total: self.items_total,
            items,
            spp: self.spp,
            tonemap: self.tonemap.clone(),
        };
        state::write(path, &info, film)
            .map_err(|e| Failure::other(format!("{}: cannot write the state: {e}", path.display())))
    }

    /// Problems met writing periodic checkpoints (reported once the render ends).
    pub fn errors(&self) -> Vec<String> {
        std::mem::take(&mut *self.errors.lock().unwrap())
    }
}

/// An observer that forwards to `inner` and writes checkpoints.
pub struct Checkpointing<'a> {
    pub inner: &'a dyn RenderObserver,
    pub saver: &'a Saver,
}

impl RenderObserver for Checkpointing<'_> {
    fn progress(&self, p: &Progress) {
        self.inner.progress(p);
    }
    fn pass_done(&self, film: &Film, spp: u32) {
        self.inner.pass_done(film, spp);
    }
    fn note(&self, line: &str) {
        self.inner.note(line);
    }
    fn checkpoint(&self, film: &Film, items: Range<u64>) {
        self.inner.checkpoint(film, items.clone());
        let Some((path, every)) = &self.saver.checkpoint else {
            return;
        };
        let mut last = self.saver.last.lock().unwrap();
        if last.is_some_and(|t| t.elapsed() < *every) {
            return;
        }
        if let Err(e) = self.saver.write(path, film, items) {
            self.saver.errors.lock().unwrap().push(e.message);
        }
        *last = Some(Instant::now());
    }
}

/// Reads a checkpoint to resume, refusing another render's (exit code 2).
pub fn read_resume(path: &Path, identity: u64) -> Result<FilmState, Failure> {
    let s = FilmState::read(path).map_err(Failure::input)?;
    s.check_identity(identity, &format!("--resume {}", path.display()))
        .map_err(Failure::input)?;
    Ok(s)
}

/// `penumbra merge`: states → the images (and `--stderr`) of the whole render.
pub fn cmd_merge(
    states: &[PathBuf],
    outputs: &[PathBuf],
    stderr: Option<&Path>,
) -> Result<(), Failure> {
    crate::check_outputs(outputs)?;
    if let Some(se) = stderr {
        crate::check_outputs(&[se.to_path_buf()])?;
    }
    let start = Instant::now();
    let whole = state::merge_files(states).map_err(Failure::input)?;
    let image = whole.film.develop();
    for o in outputs {
        if o.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("state"))
        {
            whole
                .write(o)
                .map_err(|e| Failure::other(format!("{}: {e}", o.display())))?;
        } else {
            write_image_tonemapped(o, &image, whole.info.tonemap.as_ref())
                .map_err(Failure::other)?;
        }
    }
    if let Some(se) = stderr {
        write_image(se, &whole.film.develop_stderr()).map_err(Failure::other)?;
    }
    eprintln!(
        "merged {} state(s) of {} ({} items) in {:.2} s",
        states.len(),
        whole.info.description,
        whole.info.items_total,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_parsing_and_ranges() {
        assert_eq!(
            parse_shard("2/7"),
            Ok(Shard {
                index: Some(2),
                count: 7
            })
        );
        assert_eq!(parse_shard("auto/3").unwrap().index, None);
        for bad in ["7/7", "1", "a/3", "0/0", "-1/3"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
        // K ranges cover 0..n once, for n below and above K.
        for n in [0u64, 1, 5, 1000, 4097] {
            for k in [1u32, 3, 7] {
                let mut at = 0;
                for i in 0..k {
                    let r = build::spec::shard_items(i, k, n);
                    assert_eq!(r.start, at);
                    at = r.end;
                }
                assert_eq!(at, n);
            }
        }
    }
}
