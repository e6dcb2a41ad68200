//! Start-point sampling in the optimiser's unit box (the sweep's, the fits' anchors', the
//! diagnosis's and the profile's multistarts).

use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Latin-hypercube sample of `n` points in [0, 1]^k: each coordinate's n values fall one in
/// each of n equal strata, in a random order; drawn serially from `rng`.
pub fn latin_hypercube(n: usize, k: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let mut pts = vec![vec![0.0; k]; n];
    for j in 0..k {
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let s = rng.gen_range(0..=i);
            perm.swap(i, s);
        }
        for i in 0..n {
            pts[i][j] = (perm[i] as f64 + rng.gen::<f64>()) / n as f64;
        }
    }
    pts
}
