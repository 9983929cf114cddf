//! Raw inputs told apart by their bits: the hash and the equality with which the distance
//! tables find an input they already hold.

use std::hash::Hasher;

/// The map's hasher: its keys are already hashes ([`hash_bits`]), so they are taken as
/// they are instead of being hashed again.
#[derive(Default)]
pub(super) struct Prehashed(u64);

impl Hasher for Prehashed {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 = (self.0 << 8) | u64::from(*b);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = v;
    }
}

/// Hash of the bits of a raw input: FxHash's mix in four independent chains (one long
/// chain of dependent multiplies would make a look-up wait on every value in turn).
pub(super) fn hash_bits(x: &[f64]) -> u64 {
    const K: u64 = 0x51_7c_c1_b7_27_22_0a_95;
    let mix = |h: u64, v: &f64| (h.rotate_left(5) ^ v.to_bits()).wrapping_mul(K);
    let mut h = [0u64; 4];
    let quads = x.chunks_exact(4);
    let rest = quads.remainder();
    for q in quads {
        for (h, v) in h.iter_mut().zip(q) {
            *h = mix(*h, v);
        }
    }
    let h = h[0] ^ h[1].rotate_left(16) ^ h[2].rotate_left(32) ^ h[3].rotate_left(48);
    rest.iter().fold(h, mix).wrapping_mul(K)
}

pub(super) fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}
