//! Little-endian fields off the front of a fuzzer's input.

/// Reads fields in order; every read is `None` once the input runs out.
pub struct Reader<'a> {
    rest: &'a [u8],
}

impl<'a> Reader<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Reader { rest: data }
    }

    pub fn array<const N: usize>(&mut self) -> Option<[u8; N]> {
        let (head, rest) = self.rest.split_first_chunk::<N>()?;
        self.rest = rest;
        Some(*head)
    }

    pub fn u8(&mut self) -> Option<u8> {
        self.array::<1>().map(|[b]| b)
    }

    pub fn u32(&mut self) -> Option<u32> {
        self.array().map(u32::from_le_bytes)
    }

    pub fn u64(&mut self) -> Option<u64> {
        self.array().map(u64::from_le_bytes)
    }

    pub fn f64(&mut self) -> Option<f64> {
        self.array().map(f64::from_le_bytes)
    }

    pub fn f64s<const N: usize>(&mut self) -> Option<[f64; N]> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64()?;
        }
        Some(out)
    }
}

/// Appends `v` as little-endian f64s (the inverse of [`Reader::f64s`]).
pub fn put_f64s(out: &mut Vec<u8>, v: &[f64]) {
    for x in v {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

/// `bytes` with a header's length and CRC-32 fields (little-endian u32 at `len_at` and
/// `crc_at`) made to match the `header`-byte header's body, so that a mutated body gets past
/// the checksum to the decoder.
pub fn seal(bytes: &[u8], header: usize, len_at: usize, crc_at: usize) -> Vec<u8> {
    let mut out = bytes.to_vec();
    if out.len() >= header {
        let len = (out.len() - header) as u32;
        let crc = prf_shared::blob::crc32(&out[header..]);
        out[len_at..len_at + 4].copy_from_slice(&len.to_le_bytes());
        out[crc_at..crc_at + 4].copy_from_slice(&crc.to_le_bytes());
    }
    out
}
