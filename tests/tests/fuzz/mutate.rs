//! Mutated payloads: a valid encoding with bytes flipped, inserted, deleted, repeated or replaced by tokens that
//! parsers find hard (huge exponents, NaN, deep nesting, boundary integers).

use proptest::collection::vec;
use proptest::prelude::*;

/// Tokens spliced into text payloads.
const TOKENS: &[&str] = &[
    "NaN",
    "Infinity",
    "-Infinity",
    "1e999",
    "-1e999",
    "1e-999",
    "-0",
    "0.0",
    "18446744073709551616",
    "-9223372036854775809",
    "4294967296",
    "1e300",
    "null",
    "true",
    "[]",
    "{}",
    "\"\"",
    "[[[[[[[[[[[[[[[[",
    "]]]]]",
    "\"\\ud800\"",
    ",",
    ":",
    "\u{feff}",
    "// c\n",
    "/*",
];

/// One edit of a byte string.
#[derive(Debug, Clone)]
pub enum Edit {
    /// Flips bit `bit` of the byte at `at`.
    Flip { at: usize, bit: u8 },
    /// Inserts `byte` before `at`.
    Insert { at: usize, byte: u8 },
    /// Deletes `len` bytes from `at`.
    Delete { at: usize, len: usize },
    /// Sets the byte at `at`.
    Set { at: usize, byte: u8 },
    /// Splices token `token` of [`TOKENS`] in place of `len` bytes at `at`.
    Token { at: usize, token: usize, len: usize },
    /// Repeats the `len` bytes at `at` `times` times.
    Repeat { at: usize, len: usize, times: usize },
    /// Cuts the payload at `at`.
    Truncate { at: usize },
}

impl Edit {
    /// Applies the edit (positions are taken modulo the length).
    fn apply(&self, b: &mut Vec<u8>) {
        let at = |i: usize, extra: usize| if b.is_empty() { 0 } else { i % (b.len() + extra) };
        match *self {
            Edit::Flip { at: i, bit } if !b.is_empty() => {
                let i = at(i, 0);
                b[i] ^= 1 << (bit % 8);
            }
            Edit::Set { at: i, byte } if !b.is_empty() => {
                let i = at(i, 0);
                b[i] = byte;
            }
            Edit::Flip { .. } | Edit::Set { .. } => {}
            Edit::Insert { at: i, byte } => {
                let i = at(i, 1);
                b.insert(i, byte);
            }
            Edit::Delete { at: i, len } => {
                let i = at(i, 0);
                let end = (i + len).min(b.len());
                b.drain(i..end);
            }
            Edit::Token { at: i, token, len } => {
                let i = at(i, 1);
                let end = (i + len).min(b.len());
                b.splice(i..end, TOKENS[token % TOKENS.len()].bytes());
            }
            Edit::Repeat { at: i, len, times } => {
                let i = at(i, 0);
                let end = (i + len).min(b.len());
                let chunk = b[i..end].to_vec();
                for _ in 0..times {
                    b.splice(end..end, chunk.iter().copied());
                }
            }
            Edit::Truncate { at: i } => {
                let i = at(i, 1);
                b.truncate(i);
            }
        }
    }
}

fn edit() -> impl Strategy<Value = Edit> {
    let at = any::<usize>();
    prop_oneof![
        3 => (at, 0..8u8).prop_map(|(at, bit)| Edit::Flip { at, bit }),
        2 => (at, any::<u8>()).prop_map(|(at, byte)| Edit::Insert { at, byte }),
        2 => (at, 1..8usize).prop_map(|(at, len)| Edit::Delete { at, len }),
        2 => (at, prop_oneof![any::<u8>(), Just(0u8), Just(0xff), Just(0x80)])
            .prop_map(|(at, byte)| Edit::Set { at, byte }),
        3 => (at, any::<usize>(), 0..6usize).prop_map(|(at, token, len)| Edit::Token { at, token, len }),
        1 => (at, 1..16usize, 1..8usize).prop_map(|(at, len, times)| Edit::Repeat { at, len, times }),
        1 => at.prop_map(|at| Edit::Truncate { at }),
    ]
}

/// A payload: one of `seeds` (by index) and the edits that mutate it.
#[derive(Debug, Clone)]
pub struct Mutated {
    /// Which seed.
    pub seed: usize,
    /// The edits, in order.
    pub edits: Vec<Edit>,
}

impl Mutated {
    /// The mutated bytes of `seeds[self.seed]`.
    pub fn bytes(&self, seeds: &[Vec<u8>]) -> Vec<u8> {
        let mut b = seeds[self.seed % seeds.len()].clone();
        for e in &self.edits {
            e.apply(&mut b);
        }
        b
    }
}

/// Mutations of one of `n` seeds: 1 to 8 edits.
pub fn mutated(n: usize) -> impl Strategy<Value = Mutated> {
    (0..n, vec(edit(), 1..=8)).prop_map(|(seed, edits)| Mutated { seed, edits })
}
