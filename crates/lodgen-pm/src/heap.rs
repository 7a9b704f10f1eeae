//! A 4-ary min-heap for the contraction loop.
//!
//! `std::collections::BinaryHeap` is binary: a pop walks ~log₂ n levels and
//! each level is a cache miss once the heap outgrows the cache (the bunny's
//! pair heap holds a few hundred thousand entries; profiling showed ~45 % of
//! the loop in `BinaryHeap::pop`). With four children per node and 16-byte
//! entries, the children of a node share one 64-byte cache line and the tree
//! is half as deep.
//!
//! Also [`radix_sort_by_key`], the stable LSD radix sort that orders each
//! contraction pass (a comparison sort of the pass's pairs was a quarter of
//! all instructions on the bunny).
//!
//! Owns only the ordering containers; what an entry means is `collapse`'s.

/// Logical node `i` lives at `data[i + PAD]`: with the root at slot 3, the
/// four children of any node (`4i+1 ..= 4i+4`, slots `4(i+1) ..`) start on a
/// multiple of four entries, i.e. on one 64-byte line for 16-byte entries.
const PAD: usize = 3;

/// A 4-ary min-heap ordered by `Ord` (smallest first).
#[derive(Clone, Debug, Default)]
pub struct QuadHeap<T> {
    /// `PAD` filler slots, then the heap.
    data: Vec<T>,
}

impl<T: Ord + Copy> QuadHeap<T> {
    /// Build from unordered items in O(n).
    pub fn from_vec(items: Vec<T>) -> Self {
        let Some(&first) = items.first() else {
            return QuadHeap { data: Vec::new() };
        };
        let mut data = Vec::with_capacity(items.len() + PAD);
        data.extend(std::iter::repeat_n(first, PAD));
        data.extend_from_slice(&items);
        let mut h = QuadHeap { data };
        let n = h.len();
        if n > 1 {
            for i in (0..=(n - 2) / 4).rev() {
                h.sift_down(i);
            }
        }
        h
    }

    pub fn len(&self) -> usize {
        self.data.len().saturating_sub(PAD)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn push(&mut self, item: T) {
        if self.data.is_empty() {
            self.data.extend(std::iter::repeat_n(item, PAD));
        }
        self.data.push(item);
        let mut i = self.len() - 1;
        while i > 0 {
            let parent = (i - 1) / 4;
            if item < self.data[parent + PAD] {
                self.data[i + PAD] = self.data[parent + PAD];
                i = parent;
            } else {
                break;
            }
        }
        self.data[i + PAD] = item;
    }

    pub fn pop(&mut self) -> Option<T> {
        if self.is_empty() {
            return None;
        }
        let last = self.data.pop()?;
        if self.is_empty() {
            return Some(last);
        }
        let top = self.data[PAD];
        self.data[PAD] = last;
        self.sift_down(0);
        Some(top)
    }

    /// Remove every item (in no particular order).
    pub fn drain(&mut self) -> std::vec::Drain<'_, T> {
        let start = PAD.min(self.data.len());
        self.data.drain(start..)
    }

    fn sift_down(&mut self, mut i: usize) {
        let d = &mut self.data[PAD..];
        let n = d.len();
        let item = d[i];
        loop {
            let first = 4 * i + 1;
            if first >= n {
                break;
            }
            let end = (first + 4).min(n);
            let mut best = first;
            for c in first + 1..end {
                if d[c] < d[best] {
                    best = c;
                }
            }
            if d[best] < item {
                d[i] = d[best];
                i = best;
            } else {
                break;
            }
        }
        d[i] = item;
    }
}

/// The `u32` whose unsigned order is `f32::total_cmp`'s order.
#[inline]
pub fn f32_order_key(x: f32) -> u32 {
    let b = x.to_bits();
    if b >> 31 == 1 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// Sort `items` by `key`, stably (equal keys keep their order), in three
/// passes of 11 bits; passes whose digit is the same for every item are
/// skipped. `scratch` is reused between calls.
pub fn radix_sort_by_key<T: Copy>(
    items: &mut Vec<T>,
    scratch: &mut Vec<T>,
    key: impl Fn(&T) -> u32,
) {
    let input = std::mem::take(items);
    radix_sort_parts(vec![input], items, scratch, key);
}

/// [`radix_sort_by_key`] of the concatenation of `parts`, into `out`:
/// the first pass reads the parts directly and frees them, so they are
/// never copied into one list first (peak memory).
pub fn radix_sort_parts<T: Copy>(
    parts: Vec<Vec<T>>,
    out: &mut Vec<T>,
    scratch: &mut Vec<T>,
    key: impl Fn(&T) -> u32,
) {
    const BITS: u32 = 11;
    const BUCKETS: usize = 1 << BITS;
    let n: usize = parts.iter().map(Vec::len).sum();
    let Some(&first) = parts.iter().find_map(|p| p.first()) else {
        out.clear();
        return;
    };
    let mut counts = vec![[0u32; BUCKETS]; 3];
    for it in parts.iter().flatten() {
        let k = key(it);
        for (d, c) in counts.iter_mut().enumerate() {
            c[((k >> (BITS * d as u32)) as usize) & (BUCKETS - 1)] += 1;
        }
    }
    let mut parts = Some(parts);
    for (d, c) in counts.iter_mut().enumerate() {
        if c.iter().any(|&x| x as usize == n) {
            continue; // this digit is the same for every item
        }
        let mut sum = 0;
        for x in c.iter_mut() {
            let v = *x;
            *x = sum;
            sum += v;
        }
        let shift = BITS * d as u32;
        let mut scatter = |dst: &mut Vec<T>, it: &T| {
            let b = ((key(it) >> shift) as usize) & (BUCKETS - 1);
            dst[c[b] as usize] = *it;
            c[b] += 1;
        };
        if let Some(parts) = parts.take() {
            out.clear();
            out.resize(n, first);
            for part in parts {
                for it in &part {
                    scatter(out, it);
                }
            }
        } else {
            scratch.clear();
            scratch.resize(n, first);
            for it in out.iter() {
                scatter(scratch, it);
            }
            std::mem::swap(out, scratch);
        }
    }
    if let Some(parts) = parts {
        // every digit was constant: already in order
        out.clear();
        out.reserve(n);
        for part in parts {
            out.extend_from_slice(&part);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn pops_in_sorted_order(mut v in prop::collection::vec(any::<(u16, u8)>(), 0..300),
                                extra in prop::collection::vec(any::<(u16, u8)>(), 0..50)) {
            let mut h = QuadHeap::from_vec(v.clone());
            for &x in &extra {
                h.push(x);
            }
            v.extend_from_slice(&extra);
            v.sort_unstable();
            let mut out = Vec::new();
            while let Some(x) = h.pop() {
                out.push(x);
            }
            prop_assert_eq!(out, v);
        }

        #[test]
        fn radix_sort_is_a_stable_sort(v in prop::collection::vec((any::<f32>(), any::<u16>()), 0..3000)) {
            let mut expected = v.clone();
            expected.sort_by(|a, b| a.0.total_cmp(&b.0)); // stable
            let mut got = v;
            radix_sort_by_key(&mut got, &mut Vec::new(), |x| f32_order_key(x.0));
            let bits = |w: &[(f32, u16)]| w.iter().map(|x| (x.0.to_bits(), x.1)).collect::<Vec<_>>();
            prop_assert_eq!(bits(&got), bits(&expected));
        }
    }
}
