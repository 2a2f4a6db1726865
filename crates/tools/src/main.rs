//! `penumbra-tools`: generators of Penumbra's checked-in data.
//!
//! - `rgb2spec` — the RGB → spectrum coefficient table of Jakob & Hanika 2019 for linear sRGB
//!   (`rgb2spec.rs`), checked by the upsampling round trip (`roundtrip.rs`) and written to
//!   `crates/render/src/spectral/srgb_to_spectrum.bin`.
//! - `ior-spectra` — Mitsuba 3's measured conductor spectra (`data/ior/*.eta.spd`, `*.k.spd`)
//!   as a Rust table (`ior_spectra.rs`), written to
//!   `crates/scene/src/formats/mitsuba/ior_data.rs`.
//!
//! The CIE tables themselves come from `crates/base/src/gen_cie.py`.

mod ior_spectra;
mod rgb2spec;
mod roundtrip;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "penumbra-tools",
    about = "Generators of Penumbra's checked-in data"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Compute the sRGB → spectrum coefficient table (Jakob & Hanika 2019) and write it.
    Rgb2spec {
        /// Nodes per axis (pbrt-v4 uses 64).
        #[arg(long, default_value_t = 64)]
        res: usize,
        /// Worker threads (the columns of the table are independent).
        #[arg(long, default_value_t = 1)]
        threads: usize,
        /// Where to write the table.
        #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/../render/src/spectral/srgb_to_spectrum.bin"))]
        out: PathBuf,
        /// Compute and check only; write nothing.
        #[arg(long)]
        dry_run: bool,
    },
    /// Read Mitsuba 3's measured conductor spectra (`data/ior/<name>.eta.spd`, `.k.spd`) and
    /// write them as a checked-in Rust table.
    IorSpectra {
        /// Mitsuba 3's `data/ior` directory (in a pip install: `site-packages/mitsuba/data/ior`).
        #[arg(long)]
        dir: PathBuf,
        /// Where to write the table.
        #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/../scene/src/formats/mitsuba/ior_data.rs"))]
        out: PathBuf,
    },
}

fn main() {
    let cli = Cli::parse();
    match cli.command {
        Command::IorSpectra { dir, out } => {
            let materials = match ior_spectra::read_dir(&dir) {
                Ok(m) => m,
                Err(e) => {
                    eprintln!("{e}");
                    std::process::exit(2);
                }
            };
            let command = "cargo run -p penumbra-tools --release -- ior-spectra --dir \
                           <site-packages>/mitsuba/data/ior";
            let text = ior_spectra::rust_table(&materials, &dir.display().to_string(), command);
            if let Err(e) = std::fs::write(&out, &text) {
                eprintln!("cannot write {}: {e}", out.display());
                std::process::exit(3);
            }
            println!(
                "wrote {} ({} materials, {} bytes)",
                out.display(),
                materials.len(),
                text.len()
            );
        }
        Command::Rgb2spec {
            res,
            threads,
            out,
            dry_run,
        } => {
            if !(2..=256).contains(&res) {
                eprintln!("--res must be in 2..=256");
                std::process::exit(2);
            }
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads.max(1))
                .build()
                .expect("a thread pool");
            let start = Instant::now();
            let (table, report) = pool.install(|| rgb2spec::compute_srgb_table(res));
            let secs = start.elapsed().as_secs_f64();
            println!(
                "res {res}: {} fits, {:.1} iterations each on average, in {secs:.1} s on {} \
                 thread(s); largest Lab residual {:.2e} at rgb {:?}; {} above 1e-3",
                report.fits,
                report.iterations as f64 / report.fits.max(1) as f64,
                threads.max(1),
                report.max_residual,
                report.worst_rgb,
                report.unconverged
            );
            for (scale, n) in [(1.0, 16), (5.0, 16)] {
                let [a, u, i] = roundtrip::round_trip(&table, n, scale);
                println!(
                    "round trip, {n}³ grid (unbounded and illuminant × {scale}): max abs error \
                     albedo {:.2e} at {:?}, unbounded {:.2e} at {:?}, illuminant {:.2e} at {:?}",
                    a.error, a.rgb, u.error, u.rgb, i.error, i.rgb
                );
            }
            let bytes = table.to_bytes();
            if dry_run {
                println!("dry run: {} bytes not written", bytes.len());
                return;
            }
            if let Err(e) = std::fs::write(&out, &bytes) {
                eprintln!("cannot write {}: {e}", out.display());
                std::process::exit(3);
            }
            println!("wrote {} ({} bytes)", out.display(), bytes.len());
        }
    }
}
