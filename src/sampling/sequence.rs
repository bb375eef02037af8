//! Low-discrepancy 2-D points: the first two dimensions of the Sobol sequence, i.e. the (0,2)-sequence
//! pbrt-v3's `02sequence` sampler uses, with random XOR (digit) scrambling so each pixel, sample and
//! dimension gets an independent, still well-stratified, point set.

/// The `i`-th point of the scrambled (0,2)-sequence in [0,1)²; `scramble` holds two 32-bit XOR masks.
/// Any power-of-two prefix is a (0, m, 2)-net: one point in every elementary interval.
#[inline]
pub fn sobol02(i: u32, scramble: [u32; 2]) -> [f32; 2] {
    let x = i.reverse_bits() ^ scramble[0];
    let y = sobol_dim1(i) ^ scramble[1];
    [to_unit(x), to_unit(y)]
}

/// The second Sobol dimension (generator matrix of x+1): the XOR of the matrix columns of `i`'s set bits,
/// looked up a byte of `i` at a time in [`DIM1_BYTES`] (no data-dependent branch; the loop it replaces
/// mispredicted on every sample, `sobol_dim1_bitwise` in the tests).
#[inline]
fn sobol_dim1(i: u32) -> u32 {
    let t = &DIM1_BYTES;
    t[0][(i & 0xff) as usize]
        ^ t[1][((i >> 8) & 0xff) as usize]
        ^ t[2][((i >> 16) & 0xff) as usize]
        ^ t[3][(i >> 24) as usize]
}

/// `DIM1_BYTES[b][v]`: the XOR of the second Sobol dimension's matrix columns 8b..8b+8 selected by the bits
/// of `v` (column j is `v_j`, where v_0 = 2³¹ and v_{j+1} = v_j ^ (v_j >> 1)).
static DIM1_BYTES: [[u32; 256]; 4] = dim1_bytes();

const fn dim1_bytes() -> [[u32; 256]; 4] {
    let mut columns = [0u32; 32];
    let mut v: u32 = 1 << 31;
    let mut j = 0;
    while j < 32 {
        columns[j] = v;
        v ^= v >> 1;
        j += 1;
    }
    let mut t = [[0u32; 256]; 4];
    let mut b = 0;
    while b < 4 {
        let mut x = 0;
        while x < 256 {
            let mut r = 0u32;
            let mut bit = 0;
            while bit < 8 {
                if x & (1 << bit) != 0 {
                    r ^= columns[8 * b + bit];
                }
                bit += 1;
            }
            t[b][x] = r;
            x += 1;
        }
        b += 1;
    }
    t
}

#[inline]
fn to_unit(bits: u32) -> f32 {
    ((bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)).min(super::rng::ONE_MINUS_EPSILON)
}

/// Element `i` of a pseudo-random permutation of 0..len selected by `key` (Kensler 2013, "Correlated
/// Multi-Jittered Sampling"): lets each pixel visit its stratified samples in its own order without storing
/// a permutation. `i` must be below `len` (the walk that brings the hash back into 0..len ends only then).
pub fn permute(i: u32, len: u32, key: u32) -> u32 {
    if len <= 1 {
        return 0;
    }
    let w = mask(len);
    // Cycle-walking: hash until the value lands inside 0..len (at once when len is a power of two).
    let mut i = permute_round(i, w, key);
    while i >= len {
        i = permute_round(i, w, key);
    }
    permute_finish(i, len, key)
}

/// `out[j] = permute(first + j, len, key)` for indices first + j < len: the same values, eight at a time
/// with AVX2 where the CPU has it (a pixel's whole row of sample orders, which
/// [`super::pixel_samples::PixelSamples`] tabulates; one at a time the hash's multiplies were the draws'
/// largest cost).
pub fn permute_range(first: u32, out: &mut [u32], len: u32, key: u32) {
    #[cfg(target_arch = "x86_64")]
    if len > 1 && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2.
        unsafe { permute_range_avx2(first, out, len, key) };
        return;
    }
    for (j, o) in out.iter_mut().enumerate() {
        *o = permute(first.wrapping_add(j as u32), len, key);
    }
}

/// [`permute_range`] with the first round of the hash in 8 lanes; lanes that land outside 0..len walk on
/// one at a time, as [`permute`] does.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn permute_range_avx2(first: u32, out: &mut [u32], len: u32, key: u32) {
    use std::arch::x86_64::*;
    let w = mask(len);
    let c = |v: u32| _mm256_set1_epi32(v as i32);
    let (vw, vp) = (c(w), c(key));
    let (p16, p8, p23) = (c(key >> 16), c(key >> 8), c(key >> 23));
    let m27 = c(1 | key >> 27);
    let lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let mut chunks = out.chunks_exact_mut(8);
    let mut at = first;
    for chunk in &mut chunks {
        let mut i = _mm256_add_epi32(c(at), lanes);
        // `permute_round`, operation for operation (wrapping 32-bit products, logical shifts).
        i = _mm256_xor_si256(i, vp);
        i = _mm256_mullo_epi32(i, c(0xe170_893d));
        i = _mm256_xor_si256(i, p16);
        i = _mm256_xor_si256(i, _mm256_srli_epi32::<4>(_mm256_and_si256(i, vw)));
        i = _mm256_xor_si256(i, p8);
        i = _mm256_mullo_epi32(i, c(0x0929_eb3f));
        i = _mm256_xor_si256(i, p23);
        i = _mm256_xor_si256(i, _mm256_srli_epi32::<1>(_mm256_and_si256(i, vw)));
        i = _mm256_mullo_epi32(i, m27);
        i = _mm256_mullo_epi32(i, c(0x6935_fa69));
        i = _mm256_xor_si256(i, _mm256_srli_epi32::<11>(_mm256_and_si256(i, vw)));
        i = _mm256_mullo_epi32(i, c(0x74dc_b303));
        i = _mm256_xor_si256(i, _mm256_srli_epi32::<2>(_mm256_and_si256(i, vw)));
        i = _mm256_mullo_epi32(i, c(0x9e50_1cc3));
        i = _mm256_xor_si256(i, _mm256_srli_epi32::<2>(_mm256_and_si256(i, vw)));
        i = _mm256_mullo_epi32(i, c(0xc860_a3df));
        i = _mm256_and_si256(i, vw);
        i = _mm256_xor_si256(i, _mm256_srli_epi32::<5>(i));
        let mut round = [0u32; 8];
        // SAFETY: `round` holds 8 u32, the 32 bytes stored.
        unsafe { _mm256_storeu_si256(round.as_mut_ptr().cast(), i) };
        for (o, mut v) in chunk.iter_mut().zip(round) {
            while v >= len {
                v = permute_round(v, w, key);
            }
            *o = permute_finish(v, len, key);
        }
        at = at.wrapping_add(8);
    }
    for (j, o) in chunks.into_remainder().iter_mut().enumerate() {
        *o = permute(at.wrapping_add(j as u32), len, key);
    }
}

/// The smallest all-ones mask covering len − 1.
#[inline(always)]
fn mask(len: u32) -> u32 {
    let mut w = len - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    w
}

/// One round of Kensler's hash of `i` under mask `w` and key `p`.
#[inline(always)]
fn permute_round(mut i: u32, w: u32, p: u32) -> u32 {
    i ^= p;
    i = i.wrapping_mul(0xe170_893d);
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8;
    i = i.wrapping_mul(0x0929_eb3f);
    i ^= p >> 23;
    i ^= (i & w) >> 1;
    i = i.wrapping_mul(1 | p >> 27);
    i = i.wrapping_mul(0x6935_fa69);
    i ^= (i & w) >> 11;
    i = i.wrapping_mul(0x74dc_b303);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0x9e50_1cc3);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0xc860_a3df);
    i &= w;
    i ^= i >> 5;
    i
}

/// The permuted index from a hash value `i` < len: offset by the key, wrapped into 0..len.
#[inline(always)]
fn permute_finish(i: u32, len: u32, p: u32) -> u32 {
    let j = i.wrapping_add(p);
    // Pixel sample counts are mostly powers of two, where a mask is the remainder without a division (the
    // division was the costliest instruction of drawing a sample).
    if len.is_power_of_two() { j & (len - 1) } else { j % len }
}

#[cfg(test)]
mod tests {
    #[test]
    fn permutations_are_bijections() {
        for len in [1u32, 2, 7, 16, 100] {
            for key in [0u32, 1, 0xdead_beef] {
                let mut seen = vec![false; len as usize];
                for i in 0..len {
                    let j = permute(i, len, key) as usize;
                    assert!(!seen[j]);
                    seen[j] = true;
                }
            }
        }
    }

    use super::*;

    /// The generator-matrix product bit by bit, as the definition reads.
    fn sobol_dim1_bitwise(mut i: u32) -> u32 {
        let mut v: u32 = 1 << 31;
        let mut r = 0u32;
        while i != 0 {
            if i & 1 != 0 {
                r ^= v;
            }
            i >>= 1;
            v ^= v >> 1;
        }
        r
    }

    /// Kensler's permutation as first written: one loop, the walk inside it.
    fn permute_as_written(mut i: u32, len: u32, key: u32) -> u32 {
        if len <= 1 {
            return 0;
        }
        let w = mask(len);
        let p = key;
        loop {
            i ^= p;
            i = i.wrapping_mul(0xe170_893d);
            i ^= p >> 16;
            i ^= (i & w) >> 4;
            i ^= p >> 8;
            i = i.wrapping_mul(0x0929_eb3f);
            i ^= p >> 23;
            i ^= (i & w) >> 1;
            i = i.wrapping_mul(1 | p >> 27);
            i = i.wrapping_mul(0x6935_fa69);
            i ^= (i & w) >> 11;
            i = i.wrapping_mul(0x74dc_b303);
            i ^= (i & w) >> 2;
            i = i.wrapping_mul(0x9e50_1cc3);
            i ^= (i & w) >> 2;
            i = i.wrapping_mul(0xc860_a3df);
            i &= w;
            i ^= i >> 5;
            if i < len {
                break;
            }
        }
        (i.wrapping_add(p)) % len
    }

    #[test]
    fn permutations_one_at_a_time_and_by_rows_are_the_loop_as_written() {
        for len in [1u32, 2, 3, 7, 16, 17, 64, 100, 256, 1000, 4096, 65_537] {
            for key in [0u32, 1, 0xdead_beef, 0x8000_0001, u32::MAX] {
                // The walk ends only for indices in 0..len (an index beyond may sit on a cycle of the
                // hash that never enters 0..len), so the rows stay inside.
                for first in [0u32, 5.min(len - 1), len.saturating_sub(3)] {
                    let n = (len - first).min(213) as usize;
                    let mut row = vec![0; n];
                    permute_range(first, &mut row, len, key);
                    for (j, &got) in row.iter().enumerate() {
                        let i = first + j as u32;
                        let want = permute_as_written(i, len, key);
                        assert_eq!(permute(i, len, key), want, "len {len}, key {key:x}, i {i}");
                        assert_eq!(got, want, "row: len {len}, key {key:x}, i {i}");
                    }
                }
            }
        }
    }

    #[test]
    fn the_byte_tables_give_the_bitwise_product() {
        let mut x = 0x1234_5678u32;
        for i in (0..70_000u32).chain([u32::MAX, 1 << 31, 0xff00_ff00]) {
            assert_eq!(sobol_dim1(i), sobol_dim1_bitwise(i), "{i}");
            x = x.wrapping_mul(0x9e37_79b9).wrapping_add(i);
            assert_eq!(sobol_dim1(x), sobol_dim1_bitwise(x), "{x}");
        }
    }

    #[test]
    fn power_of_two_prefixes_are_nets() {
        // 16 points: one in each of the 16 cells for every elementary-interval shape 1×16, 2×8, 4×4, 8×2, 16×1.
        for scramble in [[0, 0], [0xdead_beef, 0x1234_5678]] {
            let pts: Vec<[f32; 2]> = (0..16).map(|i| sobol02(i, scramble)).collect();
            for kx in 0..=4 {
                let (nx, ny) = (1usize << kx, 1usize << (4 - kx));
                let mut seen = [false; 16];
                for p in &pts {
                    let c = (p[0] * nx as f32) as usize + nx * (p[1] * ny as f32) as usize;
                    assert!(!seen[c], "cell hit twice for {nx}x{ny}");
                    seen[c] = true;
                }
            }
        }
    }
}
