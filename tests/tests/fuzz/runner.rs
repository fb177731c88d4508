//! Running one target: a fixed, seeded number of cases by default (the pass CI runs), or random cases until
//! `DMP_FUZZ_SECONDS` have passed (`scripts/fuzz.sh`). A failing input is shrunk and printed with the seed that
//! found it, so that it can become a regression test.

use std::fmt::Debug;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use proptest::strategy::Strategy;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseResult, TestError, TestRng, TestRunner};

/// Seconds to fuzz each target for, from `DMP_FUZZ_SECONDS`; None for the default seeded pass.
fn fuzz_seconds() -> Option<f64> {
    let s = std::env::var("DMP_FUZZ_SECONDS").ok()?;
    let seconds: f64 = s.trim().parse().unwrap_or_else(|_| panic!("DMP_FUZZ_SECONDS=`{s}` is not a number"));
    Some(seconds)
}

/// The seed of a run: `DMP_FUZZ_SEED`, else a fixed one for the seeded pass and the clock for a timed run.
fn base_seed(timed: bool) -> u64 {
    if let Ok(s) = std::env::var("DMP_FUZZ_SEED") {
        return s.trim().parse().unwrap_or_else(|_| panic!("DMP_FUZZ_SEED=`{s}` is not an integer"));
    }
    if timed {
        SystemTime::now().duration_since(UNIX_EPOCH).map_or(1, |d| d.as_nanos() as u64)
    } else {
        0x5EED_D3F0_0000_0015
    }
}

/// The random number generator of batch `round` of target `name` (every target has its own stream of cases).
fn rng(name: &str, seed: u64, round: u64) -> TestRng {
    let mut bytes = [0u8; 32];
    bytes[..8].copy_from_slice(&seed.to_le_bytes());
    bytes[8..16].copy_from_slice(&round.to_le_bytes());
    for (i, b) in name.bytes().enumerate() {
        bytes[16 + i % 16] ^= b;
    }
    TestRng::from_seed(RngAlgorithm::ChaCha, &bytes)
}

/// Runs `check` on `cases` inputs of `strategy` (in batches of `batch` until the deadline when
/// `DMP_FUZZ_SECONDS` is set); panics with the shrunk failing input. A panic inside `check` is a failure.
pub fn fuzz<S>(name: &str, cases: u32, batch: u32, strategy: S, check: impl Fn(S::Value) -> TestCaseResult)
where
    S: Strategy,
    S::Value: Debug,
{
    let seconds = fuzz_seconds();
    let seed = base_seed(seconds.is_some());
    let started = Instant::now();
    let mut total = 0u64;
    for round in 0.. {
        let n = if seconds.is_some() { batch } else { cases };
        let config = Config {
            cases: n,
            failure_persistence: None,
            max_shrink_iters: 2_000,
            max_shrink_time: 60_000,
            ..Config::default()
        };
        let mut runner = TestRunner::new_with_rng(config, rng(name, seed, round));
        match runner.run(&strategy, &check) {
            Ok(()) => total += u64::from(n),
            Err(TestError::Fail(reason, input)) => panic!(
                "fuzz {name}: FAILED after {total} cases (DMP_FUZZ_SEED={seed}, batch {round}): {reason}\n\
                 shrunk input: {input:#?}"
            ),
            Err(TestError::Abort(reason)) => panic!("fuzz {name}: aborted: {reason}"),
        }
        match seconds {
            Some(s) if started.elapsed().as_secs_f64() < s => {}
            _ => break,
        }
    }
    println!("fuzz {name}: {total} cases in {:.1} s, 0 failures", started.elapsed().as_secs_f64());
}
