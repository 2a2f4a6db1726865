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

/// Per channel, the z statistic of the mean of the differences `a[i] − b[i]` (paired
/// samples, e.g. the pixels of two independent renders of the same image): the mean
/// difference over its standard error. Values near 0 say the two have the same mean.
pub fn z_of_mean_difference(a: &[[f32; 3]], b: &[[f32; 3]]) -> [f64; 3] {
    assert_eq!(a.len(), b.len());
    let n = a.len() as f64;
    [0, 1, 2].map(|c| {
        let d: Vec<f64> = a
            .iter()
            .zip(b)
            .map(|(x, y)| f64::from(x[c]) - f64::from(y[c]))
            .collect();
        let mean = d.iter().sum::<f64>() / n;
        let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
        mean / (var / n).sqrt().max(1e-12)
    })
}
