//! Hostile inputs (issue 18): each must end in exit 2 with a located diagnostic, never an
//! abort, a panic or unbounded memory.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn penumbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-hard-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Exit 2, no panic, and an `error: FILE:LINE:COL: …` line naming `file` whose message
/// contains `needle`.
fn assert_located_failure(out: &Output, file: &Path, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(2),
        "exit {:?}\n{stderr}",
        out.status
    );
    assert!(!stderr.contains("panicked"), "panic\n{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.starts_with("error: "))
        .unwrap_or_else(|| panic!("no error line\n{stderr}"));
    let rest = line
        .trim_start_matches("error: ")
        .strip_prefix(&*file.to_string_lossy())
        .unwrap_or_else(|| panic!("diagnostic does not start with the file: {line}"));
    let mut parts = rest.splitn(4, ':');
    assert_eq!(parts.next(), Some(""), "{line}");
    for what in ["line", "column"] {
        let n = parts.next().unwrap_or_default();
        assert!(
            n.parse::<u32>().is_ok_and(|n| n > 0),
            "no {what} number: {line}"
        );
    }
    assert!(line.contains(needle), "expected '{needle}' in: {line}");
}

/// A Mitsuba scene nested 10,000 shapes deep overflowed the stack (SIGABRT) before.
#[test]
fn deeply_nested_mitsuba_xml_is_refused() {
    let dir = temp_dir("mitsuba-deep");
    let file = dir.join("deep.xml");
    let n = 10_000;
    let text = format!(
        "<scene version=\"3.0.0\">{}{}</scene>",
        "<shape type=\"sphere\">".repeat(n),
        "</shape>".repeat(n)
    );
    std::fs::write(&file, text).unwrap();
    let out = penumbra().arg("info").arg(&file).output().unwrap();
    assert_located_failure(&out, &file, "nested more than 256 deep");
}

/// A CENG795 XML scene with 20,000 nested `<Objects>`: a stack overflow after 1.1 GB before.
#[test]
fn deeply_nested_ceng795_xml_is_refused() {
    let dir = temp_dir("ceng-deep");
    let file = dir.join("deep.xml");
    let n = 20_000;
    let text = format!(
        "<Scene>{}{}</Scene>",
        "<Objects>".repeat(n),
        "</Objects>".repeat(n)
    );
    std::fs::write(&file, text).unwrap();
    let out = penumbra().arg("info").arg(&file).output().unwrap();
    assert_located_failure(&out, &file, "nested more than 256 deep");
}

/// COLLADA nodes and CENG795 JSON already had limits (256 nodes, serde_json's 128 levels);
/// keep them.
#[test]
fn deeply_nested_collada_and_json_are_refused() {
    let dir = temp_dir("other-deep");
    let dae = dir.join("deep.dae");
    let n = 5_000;
    std::fs::write(
        &dae,
        format!(
            "<COLLADA><library_visual_scenes><visual_scene id=\"s\">{}{}</visual_scene>\
             </library_visual_scenes><scene><instance_visual_scene url=\"#s\"/></scene></COLLADA>",
            "<node>".repeat(n),
            "</node>".repeat(n)
        ),
    )
    .unwrap();
    let out = penumbra().arg("info").arg(&dae).output().unwrap();
    assert_located_failure(&out, &dae, "deep");

    let json = dir.join("deep.json");
    std::fs::write(
        &json,
        format!("{{\"Scene\": {}{}}}", "[".repeat(n), "]".repeat(n)),
    )
    .unwrap();
    let out = penumbra().arg("info").arg(&json).output().unwrap();
    assert_located_failure(&out, &json, "recursion limit");
}
