//! The mutator: deterministic (xorshift seeded through splitmix64), byte-level and token-level edits.

/// A small, fast, seedable random generator (xorshift64*).
pub struct Rng(u64);

impl Rng {
    /// A generator whose stream depends only on `seed`.
    pub fn new(seed: u64) -> Rng {
        // splitmix64 so that nearby seeds give unrelated streams; never zero.
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        Rng((z ^ (z >> 31)) | 1)
    }

    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// A number in `0..n` (`0` when `n == 0`).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 { 0 } else { (self.next() % n as u64) as usize }
    }

    /// True with probability `1/n`.
    pub fn one_in(&mut self, n: usize) -> bool {
        self.below(n) == 0
    }

    /// A random element of a non-empty slice.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Numbers that tend to break readers, written as text.
pub const INTERESTING_NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "4",
    "255",
    "256",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "-2147483648",
    "-2147483649",
    "4294967295",
    "4294967296",
    "1099511627776",
    "9223372036854775807",
    "18446744073709551616",
    "99999999999999999999999",
    "1000000000",
    "1e9",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "infinity",
    "1e38",
    "-1e38",
    "3.5e38",
    "1e308",
    "1e309",
    "1e-45",
    "1e-320",
    "0.5",
    "-0.5",
    "1.",
    ".",
    "-",
    "+",
    "1e",
    "0x10",
];

/// Integers that tend to break binary readers (written in 1, 2, 4 or 8 bytes, either byte order).
const INTERESTING_INTS: &[u64] = &[
    0,
    1,
    2,
    3,
    4,
    0x7f,
    0x80,
    0xff,
    0x7fff,
    0x8000,
    0xffff,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    1 << 40,
    u64::MAX,
    0x7fc0_0000,           // f32 NaN
    0x7f80_0000,           // f32 +inf
    0xff80_0000,           // f32 -inf
    0x7f7f_ffff,           // f32 max
    0x7ff8_0000_0000_0000, // f64 NaN
    0x7ff0_0000_0000_0000, // f64 inf
];

/// Bytes with a meaning in the text formats.
const INTERESTING_BYTES: &[u8] = b"\0\n\r\t \"[]#-+.e0123456789\xff\x80\x7f";

/// How the bytes of `data` are changed; `others` are inputs to splice from, `dict` tokens to insert.
pub struct Mutator<'a> {
    /// Inputs to splice with.
    pub others: &'a [&'a [u8]],
    /// Keywords and fragments of the target's format.
    pub dict: &'a [&'a [u8]],
    /// Inputs are cut to this many bytes.
    pub max_len: usize,
}

impl Mutator<'_> {
    /// Applies one to eight random edits to `data`.
    pub fn mutate(&self, rng: &mut Rng, data: &mut Vec<u8>) {
        let most = if rng.one_in(4) { 8 } else { 3 };
        let n = 1 + rng.below(most);
        for _ in 0..n {
            self.one(rng, data);
        }
        data.truncate(self.max_len);
    }

    fn one(&self, rng: &mut Rng, data: &mut Vec<u8>) {
        let len = data.len();
        match rng.below(14) {
            // Flip one bit.
            0 if len > 0 => {
                let i = rng.below(len);
                data[i] ^= 1 << rng.below(8);
            }
            // Set a byte to an interesting or random value.
            1 if len > 0 => {
                let i = rng.below(len);
                data[i] = if rng.one_in(2) { *rng.pick(INTERESTING_BYTES) } else { rng.next() as u8 };
            }
            // Delete a range.
            2 if len > 0 => {
                let (a, b) = range(rng, len);
                data.drain(a..b);
            }
            // Insert random or interesting bytes.
            3 => {
                let at = rng.below(len + 1);
                let k = 1 + rng.below(8);
                let bytes: Vec<u8> = (0..k)
                    .map(|_| if rng.one_in(2) { *rng.pick(INTERESTING_BYTES) } else { rng.next() as u8 })
                    .collect();
                data.splice(at..at, bytes);
            }
            // Duplicate a range, sometimes many times over (blow-ups, deep nesting).
            4 if len > 0 => {
                let (a, b) = range(rng, len);
                let chunk = data[a..b].to_vec();
                let times = if rng.one_in(8) { 1 + rng.below(200) } else { 1 };
                let at = rng.below(len + 1);
                let rep: Vec<u8> = chunk.iter().copied().cycle().take(chunk.len() * times).collect();
                data.splice(at..at, rep);
            }
            // Splice: our prefix with another input's suffix, or a chunk of another input inserted.
            5 if !self.others.is_empty() => {
                let other = *rng.pick(self.others);
                if other.is_empty() {
                    return;
                }
                if rng.one_in(2) {
                    let cut = rng.below(len + 1);
                    data.truncate(cut);
                    let from = rng.below(other.len());
                    data.extend_from_slice(&other[from..]);
                } else {
                    let (a, b) = range(rng, other.len());
                    let at = rng.below(len + 1);
                    data.splice(at..at, other[a..b].iter().copied());
                }
            }
            // Replace a number with an interesting one.
            6 | 7 => {
                if let Some((a, b)) = pick_number(rng, data) {
                    data.splice(a..b, rng.pick(INTERESTING_NUMBERS).bytes());
                }
            }
            // Replace a token with a dictionary entry.
            8 if !self.dict.is_empty() => {
                let tok = *rng.pick(self.dict);
                match pick_token(rng, data) {
                    Some((a, b)) if !rng.one_in(4) => drop(data.splice(a..b, tok.iter().copied())),
                    _ => {
                        let at = token_boundary(rng, data);
                        let mut ins = vec![b' '];
                        ins.extend_from_slice(tok);
                        ins.push(b' ');
                        data.splice(at..at, ins);
                    }
                }
            }
            // Truncate.
            9 if len > 0 => data.truncate(rng.below(len)),
            // Overwrite with an interesting binary integer (1, 2, 4 or 8 bytes, either byte order).
            10 | 11 if len > 0 => {
                let width = 1 << rng.below(4);
                let v = *rng.pick(INTERESTING_INTS);
                let v = if rng.one_in(4) { v.wrapping_add(rng.below(3) as u64).wrapping_sub(1) } else { v };
                let bytes = if rng.one_in(2) { v.to_le_bytes() } else { v.to_be_bytes() };
                let bytes: &[u8] = if rng.one_in(2) { &bytes[..width] } else { &bytes[8 - width..] };
                let at = rng.below(len);
                for (k, b) in bytes.iter().enumerate() {
                    if let Some(slot) = data.get_mut(at + k) {
                        *slot = *b;
                    }
                }
            }
            // Swap two tokens' places: move a line elsewhere.
            12 if len > 0 => {
                let (a, b) = line_range(rng, data);
                let line = data[a..b].to_vec();
                data.drain(a..b);
                let at = rng.below(data.len() + 1);
                data.splice(at..at, line);
            }
            // Add or subtract a small amount from a byte.
            _ if len > 0 => {
                let i = rng.below(len);
                data[i] = data[i].wrapping_add(rng.below(33) as u8).wrapping_sub(16);
            }
            _ => data.push(rng.next() as u8),
        }
    }
}

/// A random range of `0..len`, usually short.
fn range(rng: &mut Rng, len: usize) -> (usize, usize) {
    let a = rng.below(len);
    let max = if rng.one_in(4) { len - a } else { (len - a).min(16) };
    (a, a + 1 + rng.below(max))
}

/// A random number-like run (digits, sign, point, exponent) in `data`.
fn pick_number(rng: &mut Rng, data: &[u8]) -> Option<(usize, usize)> {
    let is_num = |c: u8| c.is_ascii_digit() || matches!(c, b'-' | b'+' | b'.' | b'e' | b'E');
    let start = rng.below(data.len().max(1));
    // Search forward (wrapping) from a random place for a digit.
    let n = data.len();
    let i = (0..n).map(|k| (start + k) % n).find(|&i| data[i].is_ascii_digit())?;
    let mut a = i;
    while a > 0 && is_num(data[a - 1]) {
        a -= 1;
    }
    let mut b = i;
    while b < n && is_num(data[b]) {
        b += 1;
    }
    Some((a, b))
}

/// A random whitespace-delimited token in `data`.
fn pick_token(rng: &mut Rng, data: &[u8]) -> Option<(usize, usize)> {
    let n = data.len();
    let start = rng.below(n.max(1));
    let i = (0..n).map(|k| (start + k) % n).find(|&i| !data[i].is_ascii_whitespace())?;
    let mut a = i;
    while a > 0 && !data[a - 1].is_ascii_whitespace() {
        a -= 1;
    }
    let mut b = i;
    while b < n && !data[b].is_ascii_whitespace() {
        b += 1;
    }
    Some((a, b))
}

/// A random position just after whitespace (or 0 / the end).
fn token_boundary(rng: &mut Rng, data: &[u8]) -> usize {
    let n = data.len();
    let start = rng.below(n + 1);
    (start..n).find(|&i| data[i].is_ascii_whitespace()).unwrap_or(n)
}

/// The byte range of a random line, newline included.
fn line_range(rng: &mut Rng, data: &[u8]) -> (usize, usize) {
    let i = rng.below(data.len());
    let a = data[..i].iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
    let b = data[i..].iter().position(|&c| c == b'\n').map_or(data.len(), |p| i + p + 1);
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_mutations() {
        let m = Mutator { others: &[b"Shape \"sphere\""], dict: &[b"WorldBegin"], max_len: 1 << 16 };
        let run = |seed| {
            let mut rng = Rng::new(seed);
            let mut data = b"Film \"image\" \"integer xresolution\" [ 16 ]".to_vec();
            for _ in 0..200 {
                m.mutate(&mut rng, &mut data);
            }
            data
        };
        assert_eq!(run(7), run(7));
        assert_ne!(run(7), run(8));
    }
}
