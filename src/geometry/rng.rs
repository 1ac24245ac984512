//! Reproducible random streams: every consumer of randomness (a training sample, a
//! shuffle, a surface sampling, a template) draws from its own ChaCha8 generator,
//! seeded from a (seed, stream) pair, so results do not depend on the number of
//! threads or on the order in which the streams are used.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The generator of stream `stream` of `seed`: the pair mixed by SplitMix64 into
/// ChaCha8's seed.
pub fn seeded_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut z = seed ^ stream.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    ChaCha8Rng::seed_from_u64(z)
}
