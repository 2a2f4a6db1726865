//! Renders split into shards, checkpointed and resumed (issue 41): the merged or resumed
//! image is the single-process render byte for byte, for the path and volume path tracers
//! and BDPT, on 1 or 2 threads, shards in any order; killed renders resume exactly;
//! foreign states are refused; the Slurm script and the Kubernetes manifest in docs/ run.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

fn penumbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-shards-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(cmd: &mut Command) -> std::process::Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{cmd:?}: {:?}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// A small deterministic generator (xorshift64*) for the shard orders and kill times.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// Renders `args` as one process and as 1, 3 and 7 shards (each shard on 1 or 2 threads,
/// rendered in a shuffled order), merges them and compares the EXR bytes.
fn shards_match(name: &str, scene: &Path, args: &[&str], rng: &mut Rng) {
    let dir = temp_dir(name);
    let single = dir.join("single.exr");
    run(penumbra()
        .arg("render")
        .arg(scene)
        .args(args)
        .args(["--threads", "2", "-q", "-o"])
        .arg(&single));
    let want = std::fs::read(&single).unwrap();
    for k in [1u32, 3, 7] {
        let mut order: Vec<u32> = (0..k).collect();
        for i in (1..order.len()).rev() {
            order.swap(i, rng.below(i as u64 + 1) as usize);
        }
        let mut parts = Vec::new();
        for &i in &order {
            let part = dir.join(format!("k{k}-{i}.state"));
            let threads = if (i + k) % 2 == 0 { "1" } else { "2" };
            run(penumbra()
                .arg("render")
                .arg(scene)
                .args(args)
                .args([
                    "--threads",
                    threads,
                    "-q",
                    "--shard",
                    &format!("{i}/{k}"),
                    "-o",
                ])
                .arg(&part));
            parts.push(part);
        }
        let merged = dir.join(format!("merged-{k}.exr"));
        run(penumbra().arg("merge").args(&parts).arg("-o").arg(&merged));
        assert!(
            std::fs::read(&merged).unwrap() == want,
            "{name}: {k} shards (order {order:?}) merge to other bytes than one process"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Acceptance 1 of issue 41: bench-cbox (path), media-homogeneous (volpath) and bench-cbox
/// with BDPT, as 1, 3 and 7 shards, merge to the single process's EXR byte for byte.
#[test]
fn shards_merge_to_the_single_render_bit_for_bit() {
    let Some(refs) = scene::testing::shared_dir("references/scenes") else {
        return;
    };
    let mut rng = Rng(0x005e_ed41);
    let small = ["-D", "resx=64", "-D", "resy=48", "--seed", "3"];
    let cbox = refs.join("bench-cbox.xml");
    let with = |extra: &[&'static str]| [&small[..], extra].concat();
    shards_match("cbox", &cbox, &with(&["--spp", "24"]), &mut rng);
    shards_match(
        "media",
        &refs.join("media-homogeneous.xml"),
        &with(&["--spp", "12"]),
        &mut rng,
    );
    shards_match(
        "bdpt",
        &cbox,
        &with(&["--spp", "6", "--integrator", "bdpt"]),
        &mut rng,
    );
}

/// Waits for `child` at most `limit`; true when it exited by itself.
fn wait_for(child: &mut std::process::Child, limit: Duration) -> bool {
    let start = std::time::Instant::now();
    while start.elapsed() < limit {
        if child.try_wait().unwrap().is_some() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    false
}

/// Acceptance 2 of issue 41: a render checkpointing after every pass, killed with SIGINT
/// and with SIGKILL at pseudo-random times (10 trials each, fixed seed), then resumed from
/// its checkpoint (or started again when it died before the first one), ends with the
/// uninterrupted render's bytes. A checkpoint of another scene or sample count is refused
/// with exit code 2.
#[cfg(unix)]
#[test]
fn killed_renders_resume_bit_for_bit() {
    let Some(refs) = scene::testing::shared_dir("references/scenes") else {
        return;
    };
    let scene = refs.join("bench-cbox.xml");
    let dir = temp_dir("resume");
    let args = [
        "-D",
        "resx=96",
        "-D",
        "resy=96",
        "--spp",
        "96",
        "--seed",
        "5",
        "--threads",
        "2",
        "-q",
        "--pass-seconds",
        "0",
    ];
    let full = dir.join("full.exr");
    let t0 = std::time::Instant::now();
    run(penumbra()
        .arg("render")
        .arg(&scene)
        .args(args)
        .arg("-o")
        .arg(&full));
    let whole = t0.elapsed();
    let want = std::fs::read(&full).unwrap();
    let mut rng = Rng(0x0041_c0de);
    let mut resumed = 0;
    for trial in 0..20 {
        let signal = if trial % 2 == 0 { "INT" } else { "KILL" };
        let cp = dir.join(format!("t{trial}.state"));
        let out = dir.join(format!("t{trial}.exr"));
        let mut child = penumbra()
            .arg("render")
            .arg(&scene)
            .args(args)
            .arg("--checkpoint")
            .arg(&cp)
            .args(["--checkpoint-interval", "0", "-o"])
            .arg(&out)
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // Somewhere in the render (its start-up included).
        let at = whole.mul_f64(0.05 + 0.9 * rng.below(1000) as f64 / 1000.0);
        if !wait_for(&mut child, at) {
            let kill = Command::new("kill")
                .args([format!("-{signal}"), child.id().to_string()])
                .status()
                .unwrap();
            assert!(kill.success());
        }
        let status = child.wait().unwrap();
        if signal == "INT" && status.code() == Some(130) {
            assert!(
                cp.exists(),
                "trial {trial}: interrupted without a checkpoint"
            );
        }
        let mut again = penumbra();
        again
            .arg("render")
            .arg(&scene)
            .args(args)
            .arg("-o")
            .arg(&out);
        if cp.exists() {
            again.arg("--resume").arg(&cp);
            resumed += 1;
        }
        run(&mut again);
        assert!(
            std::fs::read(&out).unwrap() == want,
            "trial {trial} (SIG{signal} after {at:?}): the resumed render differs"
        );
    }
    assert!(
        resumed >= 10,
        "only {resumed} of 20 trials had a checkpoint to resume"
    );

    // Another sample count, another scene: refused.
    let cp = dir.join("t0.state");
    let other_spp = penumbra()
        .arg("render")
        .arg(&scene)
        .args([
            "-D", "resx=96", "-D", "resy=96", "--spp", "32", "--seed", "5", "-q",
        ])
        .arg("--resume")
        .arg(&cp)
        .arg("-o")
        .arg(dir.join("x.exr"))
        .output()
        .unwrap();
    assert_eq!(other_spp.status.code(), Some(2));
    let err = String::from_utf8_lossy(&other_spp.stderr);
    assert!(err.contains("another render"), "{err}");
    let other_scene = penumbra()
        .arg("render")
        .arg(refs.join("media-homogeneous.xml"))
        .args([
            "-D", "resx=96", "-D", "resy=96", "--spp", "96", "--seed", "5", "-q",
        ])
        .arg("--resume")
        .arg(&cp)
        .arg("-o")
        .arg(dir.join("y.exr"))
        .output()
        .unwrap();
    assert_eq!(other_scene.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Clear refusals: a merge with a part missing or doubled names the items; a shard with
/// an image output, an integrator that cannot be split, an index out of range.
#[test]
fn merge_and_shard_refusals() {
    let scene = repo_root().join("scenes/cornell-box.xml");
    let dir = temp_dir("refusals");
    let base = ["-D", "resx=32", "-D", "resy=32", "--spp", "8", "-q"];
    for i in 0..3 {
        run(penumbra()
            .arg("render")
            .arg(&scene)
            .args(base)
            .args(["--shard", &format!("{i}/3"), "-o"])
            .arg(dir.join(format!("p{i}.state"))));
    }
    let p = |i: u32| dir.join(format!("p{i}.state"));
    let merge = |parts: &[PathBuf]| {
        penumbra()
            .arg("merge")
            .args(parts)
            .arg("-o")
            .arg(dir.join("m.exr"))
            .output()
            .unwrap()
    };
    let missing = merge(&[p(0), p(2)]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("are in no state"));
    let doubled = merge(&[p(0), p(1), p(1), p(2)]);
    assert_eq!(doubled.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&doubled.stderr).contains("are in both"));
    run(penumbra()
        .arg("merge")
        .args([p(2), p(0), p(1)])
        .arg("-o")
        .arg(dir.join("m.png")));

    for (extra, says) in [
        (
            vec!["--shard", "0/2", "-o", "x.exr"],
            "a shard writes its film state",
        ),
        (vec!["--shard", "2/2", "-o", "x.state"], "expected I/K"),
        (
            vec!["--shard", "0/2", "--integrator", "sppm", "-o", "x.state"],
            "cannot be split",
        ),
        (
            vec!["--shard", "auto/2", "-o", "x.state"],
            "none of SLURM_ARRAY_TASK_ID",
        ),
    ] {
        let out = penumbra()
            .current_dir(&dir)
            .arg("render")
            .arg(&scene)
            .args(base)
            .args(&extra)
            .env_remove("SLURM_ARRAY_TASK_ID")
            .env_remove("JOB_COMPLETION_INDEX")
            .env_remove("PENUMBRA_SHARD")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(says), "{extra:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Acceptance 3 of issue 41 (the schedulers' part): `docs/cluster/slurm-render.sh` run as
/// three array tasks (SLURM_ARRAY_TASK_ID set), then `slurm-merge.sh`; and the render
/// command of `docs/cluster/kubernetes-render.yaml` run for each completion index
/// (JOB_COMPLETION_INDEX set, `/data` standing for a folder here): both merge to the
/// single process's bytes.
#[cfg(unix)]
#[test]
fn slurm_script_and_kubernetes_manifest_render_shards() {
    let root = repo_root();
    let scene = root.join("scenes/cornell-box.xml");
    let dir = temp_dir("schedulers");
    let opts = ["-D", "resx=40", "-D", "resy=30", "--spp", "8", "-q"];
    let single = dir.join("single.exr");
    run(penumbra()
        .arg("render")
        .arg(&scene)
        .args(opts)
        .arg("-o")
        .arg(&single));
    let want = std::fs::read(&single).unwrap();

    let slurm = root.join("docs/cluster");
    let parts = dir.join("slurm-parts");
    for i in 0..3 {
        run(Command::new("bash")
            .arg(slurm.join("slurm-render.sh"))
            .arg(&scene)
            .arg("3")
            .arg(&parts)
            .args(opts)
            .env("PENUMBRA", env!("CARGO_BIN_EXE_penumbra"))
            .env("SLURM_ARRAY_TASK_ID", i.to_string())
            .env("SLURM_CPUS_PER_TASK", "1"));
    }
    let merged = dir.join("slurm.exr");
    run(Command::new("bash")
        .arg(slurm.join("slurm-merge.sh"))
        .arg(&parts)
        .arg(&merged)
        .env("PENUMBRA", env!("CARGO_BIN_EXE_penumbra")));
    assert!(
        std::fs::read(&merged).unwrap() == want,
        "Slurm shards differ"
    );

    // The manifest's container command and args (one JSON-style list each, valid YAML).
    let yaml = std::fs::read_to_string(root.join("docs/cluster/kubernetes-render.yaml")).unwrap();
    let list = |key: &str| -> Vec<String> {
        let line = yaml
            .lines()
            .find_map(|l| l.trim().strip_prefix(key))
            .unwrap_or_else(|| panic!("no {key} in the manifest"));
        serde_json::from_str(line.trim()).unwrap()
    };
    let command = list("command:");
    assert_eq!(command, ["penumbra"]);
    let completions: u32 = yaml
        .lines()
        .find_map(|l| l.trim().strip_prefix("completions:"))
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    let data = dir.join("data");
    std::fs::create_dir_all(&data).unwrap();
    std::fs::copy(&scene, data.join("scene.xml")).unwrap();
    let mut k8s_parts = Vec::new();
    for i in 0..completions {
        let mut args: Vec<String> = list("args:")
            .iter()
            .map(|a| {
                a.replace("$(JOB_COMPLETION_INDEX)", &i.to_string())
                    .replace("/data", data.to_str().unwrap())
            })
            .collect();
        assert!(args.contains(&format!("auto/{completions}")), "{args:?}");
        // The test's own resolution and samples instead of the manifest's.
        if let Some(at) = args.iter().position(|a| a == "--spp") {
            args.drain(at..at + 2);
        }
        assert!(args.iter().any(|a| a == "-q"));
        run(penumbra()
            .args(&args)
            .args(&opts[..opts.len() - 1]) // the manifest has -q
            .env("JOB_COMPLETION_INDEX", i.to_string())
            .env_remove("SLURM_ARRAY_TASK_ID"));
        k8s_parts.push(data.join(format!("part-{i}.state")));
    }
    let merged = dir.join("k8s.exr");
    run(penumbra()
        .arg("merge")
        .args(&k8s_parts)
        .arg("-o")
        .arg(&merged));
    assert!(
        std::fs::read(&merged).unwrap() == want,
        "Kubernetes shards differ"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
