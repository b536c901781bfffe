//! A sweep's long arrays as read from a knowledge base: left in the file, in place, with what
//! was added since in memory (issue 17). `prf learn --add` of one program reads the example
//! cell's Table sweep, 338 k spheres and as many keys (15 MB), to add a few thousand: decoding
//! them all into new arrays cost more than the rest of reading the sweep (on the VMs measured,
//! every new page is a fault of about 2 µs), and the build needs only the spheres' count,
//! the few that touch the cells it decides anew, and one pass over the keys.

use crate::kb::{Record, RecordBytes};
use crate::learn::KbFile;
use crate::workspace::{SeenKey, SphereSample};
use std::borrow::Cow;
use std::marker::PhantomData;
use std::ops::Range;

/// Records left in a file: the bytes of their records there.
struct InFile<T> {
    file: KbFile,
    range: Range<usize>,
    record: PhantomData<T>,
}

impl<T> Clone for InFile<T> {
    fn clone(&self) -> Self {
        InFile {
            file: self.file.clone(),
            range: self.range.clone(),
            record: PhantomData,
        }
    }
}

impl<T: Record> InFile<T> {
    /// The records `read` when they are bytes of `file` (read from it in place), whole ones.
    fn of(read: &RecordBytes<'_, T>, file: &KbFile) -> Option<Self> {
        let Cow::Borrowed(b) = &read.0 else {
            return None;
        };
        let at = (b.as_ptr() as usize).checked_sub((**file).as_ref().as_ptr() as usize)?;
        let range = at..at.checked_add(b.len())?;
        let whole = range.len() % T::SIZE == 0;
        ((**file).as_ref().get(range.clone()).is_some() && whole).then(|| InFile {
            file: file.clone(),
            range,
            record: PhantomData,
        })
    }

    fn bytes(&self) -> &[u8] {
        (*self.file)
            .as_ref()
            .get(self.range.clone())
            .unwrap_or_default()
    }

    fn len(&self) -> usize {
        self.range.len() / T::SIZE
    }

    #[inline]
    fn get(&self, i: usize) -> T {
        T::get(&self.bytes()[i * T::SIZE..(i + 1) * T::SIZE])
    }

    /// The records from index `from` on.
    fn iter_from(&self, from: usize) -> impl Iterator<Item = T> + '_ {
        let rest = self.bytes().get(from * T::SIZE..).unwrap_or_default();
        rest.chunks_exact(T::SIZE).map(T::get)
    }
}

/// The stored part's records from `from` on (none without one).
fn stored_from<T: Record>(stored: &Option<InFile<T>>, from: usize) -> impl Iterator<Item = T> {
    stored.iter().flat_map(move |s| s.iter_from(from))
}

/// The spheres of a sweep, in order: a prefix left in a file (checked when read), then the
/// ones added since.
#[derive(Clone, Default)]
pub struct Spheres {
    stored: Option<InFile<SphereSample>>,
    added: Vec<SphereSample>,
}

impl Spheres {
    /// The spheres `read`: left in `file` when they are bytes of it, else decoded.
    pub(crate) fn of(read: &RecordBytes<'_, SphereSample>, file: Option<&KbFile>) -> Self {
        match file.and_then(|f| InFile::of(read, f)) {
            Some(stored) => Spheres {
                stored: Some(stored),
                added: Vec::new(),
            },
            None => Spheres::from(read.decoded()),
        }
    }

    fn stored_len(&self) -> usize {
        self.stored.as_ref().map_or(0, InFile::len)
    }

    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.stored_len() + self.added.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sphere `i` (< [`Spheres::len`]).
    #[inline]
    pub fn get(&self, i: usize) -> SphereSample {
        match &self.stored {
            Some(s) if i < s.len() => s.get(i),
            _ => self.added[i - self.stored_len()],
        }
    }

    /// The spheres in order.
    pub fn iter(&self) -> impl Iterator<Item = SphereSample> + '_ {
        self.iter_from(0)
    }

    /// The spheres from index `from` on, in order.
    pub fn iter_from(&self, from: usize) -> impl Iterator<Item = SphereSample> + '_ {
        let added = from.saturating_sub(self.stored_len());
        let added = self.added.get(added..).unwrap_or_default();
        stored_from(&self.stored, from).chain(added.iter().copied())
    }

    /// Appends `more`, in order.
    pub fn extend(&mut self, more: impl IntoIterator<Item = SphereSample>) {
        self.added.extend(more);
    }

    /// Appends one sphere.
    pub fn push(&mut self, s: SphereSample) {
        self.added.push(s);
    }

    /// The spheres as the file's records.
    pub(crate) fn to_records(&self) -> RecordBytes<'static, SphereSample> {
        let stored = self.stored.as_ref().map_or(&[][..], InFile::bytes);
        RecordBytes::written(stored, &self.added)
    }
}

impl From<Vec<SphereSample>> for Spheres {
    fn from(added: Vec<SphereSample>) -> Self {
        Spheres {
            stored: None,
            added,
        }
    }
}

impl PartialEq for Spheres {
    /// The same spheres in the same order, wherever they are held.
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

impl std::fmt::Debug for Spheres {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Spheres")
            .field("in_file", &self.stored_len())
            .field("added", &self.added.len())
            .finish()
    }
}

/// The de-duplication keys (`SeenKey`) of a sweep's spheres, as a set: an ascending run left
/// in a file (checked when read), and the ones added since, ascending, none of them in the run.
#[derive(Clone, Default)]
pub struct Seen {
    stored: Option<InFile<SeenKey>>,
    added: Vec<SeenKey>,
}

impl Seen {
    /// The keys `read`: left in `file` when they are bytes of it and ascend, else decoded, in
    /// order, without repeats (a file whose keys do not ascend gets its set restored).
    pub(crate) fn of(read: &RecordBytes<'_, SeenKey>, file: Option<&KbFile>) -> Self {
        let ascending = read.ascending();
        match file.filter(|_| ascending).and_then(|f| InFile::of(read, f)) {
            Some(stored) => Seen {
                stored: Some(stored),
                added: Vec::new(),
            },
            None => {
                let mut keys = read.decoded();
                if !ascending {
                    keys.sort_unstable();
                    keys.dedup();
                }
                Seen {
                    stored: None,
                    added: keys,
                }
            }
        }
    }

    /// A key splitting the set into halves of about its size each (None when empty).
    pub(crate) fn middle(&self) -> Option<SeenKey> {
        match &self.stored {
            Some(s) if s.len() > 0 => Some(s.get(s.len() / 2)),
            _ => self.added.get(self.added.len() / 2).copied(),
        }
    }

    /// The entries of `sorted` (ascending by key, without repeats, none below `from`) whose
    /// key is not in the set: one sequential pass over each part of it from `from` on, the
    /// file's keys compared as integers ([`ordinal`]) without being decoded.
    pub(crate) fn unseen<'a, I>(
        &'a self,
        sorted: impl Iterator<Item = (SeenKey, I)> + 'a,
        from: Option<SeenKey>,
    ) -> impl Iterator<Item = (SeenKey, I)> + 'a {
        let stored = self.stored.as_ref().map_or(&[][..], InFile::bytes);
        let stored = stored.as_chunks::<{ SeenKey::SIZE }>().0;
        let first = from.map_or(0, |f| {
            stored.partition_point(|b| ordinal(b) < ordinal_of(&f))
        });
        let mut stored = stored[first..].iter().map(|b| ordinal(b)).peekable();
        let first = from.map_or(0, |f| self.added.partition_point(|k| *k < f));
        let mut added = self.added[first..].iter().peekable();
        sorted.filter(move |(k, _)| {
            let o = ordinal_of(k);
            while stored.next_if(|s| *s < o).is_some() {}
            while added.next_if(|s| *s < k).is_some() {}
            stored.peek() != Some(&o) && added.peek() != Some(&k)
        })
    }

    /// Adds the keys `new`, ascending, none of them in the set.
    pub(crate) fn insert(&mut self, new: &[SeenKey]) {
        insert_sorted(&mut self.added, new);
    }

    /// The keys, ascending.
    pub fn to_vec(&self) -> Vec<SeenKey> {
        let mut out = Vec::with_capacity(self.stored.as_ref().map_or(0, InFile::len));
        let mut added = self.added.iter().copied().peekable();
        for s in stored_from(&self.stored, 0) {
            while let Some(a) = added.next_if(|a| *a < s) {
                out.push(a);
            }
            out.push(s);
        }
        out.extend(added);
        out
    }

    /// The keys as the file's records, ascending.
    pub(crate) fn to_records(&self) -> RecordBytes<'static, SeenKey> {
        RecordBytes::written(&[], &self.to_vec())
    }
}

impl std::fmt::Debug for Seen {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Seen")
            .field("in_file", &self.stored.as_ref().map_or(0, InFile::len))
            .field("added", &self.added.len())
            .finish()
    }
}

/// A [`SeenKey`] as an integer in the same order: x, y, z offset to unsigned, then the
/// sphere index (104 bits).
pub(crate) fn ordinal_of(k: &SeenKey) -> u128 {
    let u = |v: i32| (v as u32 ^ 0x8000_0000) as u128;
    u(k.0) << 72 | u(k.1) << 40 | u(k.2) << 8 | k.3 as u128
}

/// [`ordinal_of`] the key whose record is `b`.
#[inline]
fn ordinal(b: &[u8]) -> u128 {
    ordinal_of(&SeenKey::get(b))
}

/// Inserts the sorted keys `new`, none of them in the sorted `seen`, in place: merged from
/// the back, so only the keys after the first insertion move and no new array is allocated.
fn insert_sorted(seen: &mut Vec<SeenKey>, new: &[SeenKey]) {
    let n = seen.len();
    seen.resize(n + new.len(), (0, 0, 0, 0));
    // seen[..i] and new[..j] are still to be placed, before seen[i + j..].
    let (mut i, mut j) = (n, new.len());
    while j > 0 {
        let w = i + j - 1;
        if i > 0 && seen[i - 1] > new[j - 1] {
            seen[w] = seen[i - 1];
            i -= 1;
        } else {
            seen[w] = new[j - 1];
            j -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};
    use std::collections::BTreeSet;
    use std::sync::Arc;

    /// A file of `records` between a few other bytes, and where they lie in it.
    fn file_of<T: Record + Sync>(records: &[T]) -> (KbFile, Range<usize>) {
        let mut bytes = vec![0xa5; 7];
        bytes.extend(RecordBytes::written(&[], records).0.iter());
        let range = 7..bytes.len();
        bytes.extend([0x5a; 5]);
        (Arc::new(bytes), range)
    }

    fn borrowed<'a, T: Record>(file: &'a KbFile, range: &Range<usize>) -> RecordBytes<'a, T> {
        RecordBytes::new(Cow::Borrowed(&(**file).as_ref()[range.clone()]))
    }

    fn sphere(rng: &mut StdRng) -> SphereSample {
        let mut v = || rng.random_range(-2.0..2.0);
        SphereSample {
            centre: Vector3::new(v(), v(), v()),
            radius: rng.random_range(0.01..0.2),
            capsule: rng.random_range(0..1000),
        }
    }

    fn key(rng: &mut StdRng) -> SeenKey {
        let mut v = || rng.random_range(-40..40);
        (v(), v(), v(), rng.random_range(0..4u8))
    }

    /// Spheres left in a file read as the same spheres decoded, before and after more are
    /// added: by index, from any index on, and written back.
    #[test]
    fn spheres_left_in_the_file_read_as_decoded_ones() {
        let mut rng = StdRng::seed_from_u64(3);
        let mut reference: Vec<SphereSample> = (0..500).map(|_| sphere(&mut rng)).collect();
        let (file, range) = file_of(&reference);
        let read = borrowed(&file, &range);
        let mut left = Spheres::of(&read, Some(&file));
        let mut decoded = Spheres::of(&read, None);
        assert!(left.stored.is_some() && decoded.stored.is_none());
        let more: Vec<SphereSample> = (0..40).map(|_| sphere(&mut rng)).collect();
        for s in [&mut left, &mut decoded] {
            assert!(s.iter().eq(reference.iter().copied()));
            s.extend(more.iter().copied());
        }
        reference.extend(&more);
        for s in [&left, &decoded] {
            assert_eq!(s.len(), reference.len());
            assert!((0..reference.len()).all(|i| s.get(i) == reference[i]));
            for from in [0, 1, 499, 500, 501, 539, 540, 541] {
                let tail = reference.get(from..).unwrap_or_default();
                assert!(s.iter_from(from).eq(tail.iter().copied()), "from {from}");
            }
            assert_eq!(s.to_records(), RecordBytes::written(&[], &reference));
        }
        assert_eq!(left, decoded);
    }

    /// Keys compared as integers keep the keys' order, signs and sphere index included.
    #[test]
    fn ordinals_order_keys_as_keys_are_ordered() {
        let mut rng = StdRng::seed_from_u64(5);
        let extremes = [i32::MIN, -1, 0, 1, i32::MAX];
        let pick = |rng: &mut StdRng| {
            if rng.random_bool(0.5) {
                extremes[rng.random_range(0..extremes.len())]
            } else {
                rng.random_range(-3..3)
            }
        };
        for _ in 0..20_000 {
            let a = (
                pick(&mut rng),
                pick(&mut rng),
                pick(&mut rng),
                rng.random::<u8>(),
            );
            let b = (
                pick(&mut rng),
                pick(&mut rng),
                pick(&mut rng),
                rng.random::<u8>(),
            );
            assert_eq!(
                ordinal_of(&a).cmp(&ordinal_of(&b)),
                a.cmp(&b),
                "{a:?} {b:?}"
            );
            let mut r = [0; SeenKey::SIZE];
            a.put(&mut r);
            assert_eq!(ordinal(&r), ordinal_of(&a));
        }
    }

    /// The keys left in a file and those added since filter candidates as one set does, from
    /// any key on, and read back as the set in order; keys that do not ascend are read as
    /// their set.
    #[test]
    fn keys_left_in_the_file_filter_as_a_set() {
        let mut rng = StdRng::seed_from_u64(11);
        let mut set: BTreeSet<SeenKey> = (0..3000).map(|_| key(&mut rng)).collect();
        let kept: Vec<SeenKey> = set.iter().copied().collect();
        let (file, range) = file_of(&kept);
        let mut seen = Seen::of(&borrowed(&file, &range), Some(&file));
        assert!(seen.stored.is_some());
        let new: BTreeSet<SeenKey> = (0..800)
            .map(|_| key(&mut rng))
            .filter(|k| !set.contains(k))
            .collect();
        seen.insert(&new.iter().copied().collect::<Vec<_>>());
        set.extend(&new);
        assert_eq!(seen.to_vec(), set.iter().copied().collect::<Vec<_>>());
        let candidates: BTreeSet<SeenKey> = (0..4000).map(|_| key(&mut rng)).collect();
        for from in [None, seen.middle(), Some((0, 0, 0, 0)), Some((41, 0, 0, 0))] {
            let after = candidates.iter().filter(|k| from.is_none_or(|f| **k >= f));
            let indexed = after.clone().map(|k| (*k, ()));
            let unseen: Vec<SeenKey> = seen.unseen(indexed, from).map(|e| e.0).collect();
            let expected: Vec<SeenKey> = after.filter(|k| !set.contains(k)).copied().collect();
            assert_eq!(unseen, expected, "from {from:?}");
        }
        let mut shuffled = kept.clone();
        shuffled.extend_from_slice(&kept[..100]);
        shuffled.reverse();
        let (file, range) = file_of(&shuffled);
        let restored = Seen::of(&borrowed(&file, &range), Some(&file));
        assert!(restored.stored.is_none());
        assert_eq!(restored.to_vec(), kept);
    }
}
