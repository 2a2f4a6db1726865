//! Markov chains (MLT) in blocks: the chains of a block run in parallel and their results
//! are merged in chain order before the next block starts, so the image depends neither on
//! the thread count nor on the block size.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

/// Runs chains `0..n`, at most `block` at a time: `run(c)` is chain `c`; `merge(c, result)`
/// takes each chain's result in chain order, and `after(k)` is told after each block that
/// `k` chains are done. Stops between blocks when `cancel` is set; returns whether it was.
pub fn run_chains<T: Send>(
    n: u64,
    block: u64,
    cancel: &AtomicBool,
    run: impl Fn(u64) -> T + Sync,
    mut merge: impl FnMut(u64, T),
    mut after: impl FnMut(u64),
) -> bool {
    let mut c0 = 0u64;
    while c0 < n {
        if cancel.load(Ordering::Relaxed) {
            return true;
        }
        let c1 = (c0 + block.max(1)).min(n);
        let results: Vec<T> = (c0..c1).into_par_iter().map(&run).collect();
        for (c, r) in (c0..c1).zip(results) {
            merge(c, r);
        }
        after(c1);
        c0 = c1;
    }
    false
}
