//! Every command of README.md's `sh` blocks runs as written, from the folder it says (a `cd`
//! line), at a small size: `render` gets `--res 32x32 --spp 2`, `comp30019` `-w 32 -h 32
//! -x 1 -q 1`, `cs184` `-r 32 24 -s 4` (and `-a 2 …`); the scratch folder `/tmp/penumbra` is
//! replaced by a fresh one. `cargo run --release -p penumbra --` is the built binary; `cargo
//! test` and `cargo install` lines are not run, nor `pip`. Commands that read `../shared` are
//! skipped with a notice when it is absent, and denoising ones when Open Image Denoise is
//! (except under `CI=true`).

use std::path::{Path, PathBuf};
use std::process::Command;

const SCRATCH: &str = "/tmp/penumbra";

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// Whether the denoiser can be loaded; under `CI=true` it must be (`.ci/run` installs it).
fn oidn_or_ci() -> bool {
    let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
    ci || render::denoise::Oidn::load().is_ok()
}

/// Split a shell line into words (single and double quotes, `#` comments); `&&` separates
/// commands.
fn words(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quote = None;
    let mut in_word = false;
    for c in line.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => cur.push(c),
            (None, '\'' | '"') => {
                quote = Some(c);
                in_word = true;
            }
            (None, '#') if !in_word => break,
            (None, c) if c.is_whitespace() => {
                if in_word {
                    out.push(std::mem::take(&mut cur));
                    in_word = false;
                }
            }
            (None, c) => {
                cur.push(c);
                in_word = true;
            }
        }
    }
    if in_word {
        out.push(cur);
    }
    out
}

/// The `sh` blocks of a Markdown text, each as its lines.
fn sh_blocks(md: &str) -> Vec<Vec<String>> {
    let mut blocks = Vec::new();
    let mut cur: Option<Vec<String>> = None;
    for line in md.lines() {
        let t = line.trim();
        match &mut cur {
            None if t == "```sh" => cur = Some(Vec::new()),
            Some(b) if t == "```" => {
                blocks.push(std::mem::take(b));
                cur = None;
            }
            Some(b) => b.push(line.to_string()),
            None => {}
        }
    }
    blocks
}

/// Remove `flag` and its `n` values from `args`.
fn drop_flag(args: &mut Vec<String>, flag: &str, n: usize) {
    while let Some(i) = args.iter().position(|a| a == flag) {
        args.drain(i..(i + 1 + n).min(args.len()));
    }
}

/// The command made small enough for a test.
fn shrink(args: &mut Vec<String>) {
    match args.first().map(String::as_str) {
        Some("render") => {
            drop_flag(args, "--res", 1);
            drop_flag(args, "--spp", 1);
            args.extend(["--res", "32x32", "--spp", "2"].map(String::from));
        }
        Some("comp30019") => {
            for (flag, v) in [("-x", "1"), ("-q", "1")] {
                if let Some(i) = args.iter().position(|a| a == flag) {
                    args[i + 1] = v.into();
                }
            }
            args.extend(["-w", "32", "-h", "32"].map(String::from));
        }
        Some("cs184") => {
            drop_flag(args, "-s", 1);
            drop_flag(args, "-r", 2);
            if let Some(i) = args.iter().position(|a| a == "-a") {
                args[i + 1] = "2".into();
            }
            // Flags before the positional scene file.
            args.splice(1..1, ["-r", "32", "24", "-s", "4"].map(String::from));
        }
        _ => {}
    }
}

#[test]
fn readme_commands_run_as_written() {
    let root = repo_root();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let shared = scene::testing::shared_dir("").is_some();
    let scratch = std::env::temp_dir().join(format!("penumbra-readme-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&scratch);
    let mut ran = 0;
    for block in sh_blocks(&readme) {
        let mut cwd = root.clone();
        for line in &block {
            for cmd in line.split("&&") {
                let mut w = words(cmd);
                if w.is_empty() {
                    continue;
                }
                for a in &mut w {
                    if a.starts_with(SCRATCH) {
                        *a = a.replacen(SCRATCH, scratch.to_str().unwrap(), 1);
                    }
                }
                if !shared && w.iter().any(|a| a.contains("../shared")) {
                    eprintln!("notice: ../shared is absent; skipped: {line}");
                    if w[0] == "cd" {
                        break;
                    }
                    continue;
                }
                let mut args = match w[0].as_str() {
                    "cd" => {
                        cwd = cwd.join(&w[1]);
                        assert!(cwd.is_dir(), "{line}: no folder {}", cwd.display());
                        continue;
                    }
                    "mkdir" => {
                        std::fs::create_dir_all(cwd.join(w.last().unwrap())).unwrap();
                        continue;
                    }
                    "cargo" if w.get(1).is_some_and(|s| s == "run") => {
                        let sep = w.iter().position(|a| a == "--").expect("cargo run -- args");
                        w[sep + 1..].to_vec()
                    }
                    "cargo" => continue, // test, install, bench: not here
                    "pip" => continue,   // installs the denoiser (`.ci/run` does)
                    "penumbra"
                        if w.iter().any(|a| a == "--denoise" || a == "denoise")
                            && !oidn_or_ci() =>
                    {
                        eprintln!("notice: Open Image Denoise is absent; skipped: {line}");
                        continue;
                    }
                    "penumbra" => w[1..].to_vec(),
                    other => panic!("README command not understood by this test: {other} ({line})"),
                };
                shrink(&mut args);
                if matches!(args[0].as_str(), "render" | "comp30019" | "cs184") {
                    args.push("--quiet".into());
                }
                let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
                    .current_dir(&cwd)
                    .args(&args)
                    .output()
                    .unwrap();
                assert!(
                    out.status.success(),
                    "README command failed: {line}\n(run as: penumbra {})\n{}",
                    args.join(" "),
                    String::from_utf8_lossy(&out.stderr)
                );
                ran += 1;
            }
        }
    }
    eprintln!("{ran} README commands ran");
    assert!(ran >= 5, "only {ran} commands found in README.md");
    let _ = std::fs::remove_dir_all(&scratch);
}
