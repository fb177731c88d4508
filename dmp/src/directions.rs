//! Deterministic, nearly uniform unit directions, used to sample obstacle boundaries.

use std::f64::consts::PI;

/// `n` unit vectors of dimension `d`: in 2-D the SPEC's `theta_k = 2 pi k / n`; in 3-D a Fibonacci sphere; in 1-D
/// alternately `+1` and `-1`; above 3-D a Halton sequence pushed through the Gaussian map and normalised.
pub(crate) fn unit_directions(d: usize, n: usize) -> Vec<Vec<f64>> {
    match d {
        0 => Vec::new(),
        1 => (0..n).map(|k| vec![if k % 2 == 0 { 1.0 } else { -1.0 }]).collect(),
        2 => (0..n).map(|k| 2.0 * PI * k as f64 / n as f64).map(|t| vec![t.cos(), t.sin()]).collect(),
        3 => {
            let golden = PI * (3.0 - 5f64.sqrt());
            (0..n)
                .map(|k| {
                    let z = 1.0 - (2.0 * k as f64 + 1.0) / n as f64;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let phi = golden * k as f64;
                    vec![r * phi.cos(), r * phi.sin(), z]
                })
                .collect()
        }
        _ => (0..n).map(|k| halton_direction(d, k + 1)).collect(),
    }
}

const PRIMES: [u64; 16] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53];

fn radical_inverse(mut k: u64, base: u64) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while k > 0 {
        f /= base as f64;
        r += f * (k % base) as f64;
        k /= base;
    }
    r
}

fn halton_direction(d: usize, k: usize) -> Vec<f64> {
    let mut v: Vec<f64> = (0..d)
        .map(|i| {
            // Box-Muller on two Halton coordinates gives a Gaussian sample; its direction is uniform.
            let b1 = PRIMES[(2 * i) % PRIMES.len()];
            let b2 = PRIMES[(2 * i + 1) % PRIMES.len()];
            let u1 = radical_inverse(k as u64, b1).max(1e-12);
            let u2 = radical_inverse(k as u64 + 7, b2);
            (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
        })
        .collect();
    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if norm > 0.0 {
        v.iter_mut().for_each(|x| *x /= norm);
    } else {
        v[0] = 1.0;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_are_unit_vectors() {
        for d in 1..7 {
            for v in unit_directions(d, 37) {
                let n: f64 = v.iter().map(|x| x * x).sum();
                assert!((n - 1.0).abs() < 1e-12, "d = {d}");
            }
        }
    }
}
