//! Progress reporting: an indicatif bar with ETA and samples/s on a terminal, plain periodic
//! lines otherwise (logs, CI).

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use render::render::{Progress, RenderObserver, RenderOutcome};

pub struct Reporter {
    bar: Option<ProgressBar>,
    plain: bool,
    last_line: Mutex<Option<Instant>>,
}

const PLAIN_INTERVAL: Duration = Duration::from_secs(5);

fn rate(samples: u64, elapsed: Duration) -> String {
    let s = samples as f64 / elapsed.as_secs_f64().max(1e-9);
    if s >= 1e6 {
        format!("{:.2} M samples/s", s / 1e6)
    } else {
        format!("{:.1} k samples/s", s / 1e3)
    }
}

impl Reporter {
    pub fn new(quiet: bool) -> Reporter {
        let terminal = std::io::stderr().is_terminal();
        let bar = (!quiet && terminal).then(|| {
            let bar = ProgressBar::new(1);
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta} {msg}",
                )
                .expect("static template"),
            );
            bar
        });
        Reporter {
            bar,
            plain: !quiet && !terminal,
            last_line: Mutex::new(None),
        }
    }

    pub fn finish(&self, o: &RenderOutcome) {
        let (min, max) = o.film.pixel_bounds();
        let px = (max - min).as_u64vec2();
        let what = format!("{} spp", o.spp);
        self.finish_line(o, &what, Some(o.passes), px.x * px.y * o.spp as u64);
    }

    /// `finish` for adaptive sampling, which took `samples` pixel samples in all, `mean_spp`
    /// per pixel on average (`o.spp` is only the cap).
    pub fn finish_adaptive(&self, o: &RenderOutcome, samples: u64, mean_spp: f64) {
        let what = format!("{mean_spp:.1} spp on average (adaptive, cap {})", o.spp);
        self.finish_line(o, &what, None, samples);
    }

    fn finish_line(&self, o: &RenderOutcome, what: &str, passes: Option<u32>, samples: u64) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
        if self.bar.is_some() || self.plain {
            let passes = passes.map_or(String::new(), |n| format!("{n} passes, "));
            eprintln!(
                "rendered {what} in {:.2} s ({passes}{}){}",
                o.elapsed.as_secs_f64(),
                rate(samples, o.elapsed),
                if o.cancelled { ", interrupted" } else { "" }
            );
        }
    }
}

impl RenderObserver for Reporter {
    fn note(&self, line: &str) {
        if self.bar.is_some() || self.plain {
            match &self.bar {
                Some(bar) => bar.println(line),
                None => eprintln!("{line}"),
            }
        }
    }
    fn progress(&self, p: &Progress) {
        if let Some(bar) = &self.bar {
            bar.set_length(p.samples_total);
            bar.set_position(p.samples_done);
            bar.set_message(rate(p.samples_done, p.elapsed));
        } else if self.plain {
            let Ok(mut last) = self.last_line.lock() else {
                return;
            };
            let now = Instant::now();
            // The first line comes one interval in: the first callbacks see a few finished
            // tiles while every thread is still inside its own, and an ETA from them was
            // off by 30×.
            let Some(t) = *last else {
                *last = Some(now);
                return;
            };
            if now - t >= PLAIN_INTERVAL {
                *last = Some(now);
                let frac = p.samples_done as f64 / p.samples_total.max(1) as f64;
                let eta = if frac > 0.0 {
                    p.elapsed.as_secs_f64() * (1.0 - frac) / frac
                } else {
                    f64::NAN
                };
                eprintln!(
                    "progress {:5.1}%  elapsed {:.1} s  ETA {:.1} s  {}",
                    100.0 * frac,
                    p.elapsed.as_secs_f64(),
                    eta,
                    rate(p.samples_done, p.elapsed)
                );
            }
        }
    }
}
