//! Support for tests that read the third-party data in `../shared` beside the checkout.

use std::path::PathBuf;

/// `../shared/<rel>` beside this checkout, if it exists. When it does not, tests skip with a
/// printed notice — except under `CI=true`: CI always has the shared folder, so its absence
/// there is a broken setup, and the test fails rather than passing without testing anything.
pub fn shared_dir(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared")
        .join(rel);
    if p.exists() {
        return Some(p);
    }
    let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
    assert!(!ci, "{} is absent under CI=true", p.display());
    eprintln!("notice: {} is absent; test skipped", p.display());
    None
}
