//! Nori's own acceptance tests (`../shared/scenes/nori/pa4/tests/`, `pa5/tests/`): every file
//! holding a `ttest` or `chi2test` must pass, as `penumbra test` runs them (Šidák-corrected
//! α = 0.01 per file, fixed seed). Skipped with a notice when `../shared` is absent.

use scene::{Document, LoadOptions};

#[test]
fn nori_test_files_pass() {
    let Some(root) = scene::testing::shared_dir("scenes/nori") else {
        return;
    };
    let mut files = Vec::new();
    for dir in ["pa4/tests", "pa5/tests"] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "xml") {
                files.push(p);
            }
        }
    }
    files.sort();
    let mut ran = 0;
    for f in &files {
        let Document::Test(test) = scene::load(f, &LoadOptions::default()).expect("loads") else {
            continue;
        };
        let report = build::nori_tests::run(&test, 0).expect("runs");
        for c in &report.cases {
            println!(
                "{}: {} {}: p = {:.3e} ({})",
                f.display(),
                if c.passed { "ok" } else { "FAIL" },
                c.name,
                c.p_value,
                c.detail
            );
        }
        assert!(report.passed(), "{} fails", f.display());
        ran += 1;
    }
    assert!(ran >= 6, "only {ran} test files found");
}
