//! A 4-ary min-heap for the contraction loop.
//!
//! `std::collections::BinaryHeap` is binary: a pop walks ~log₂ n levels and
//! each level is a cache miss once the heap outgrows the cache (the bunny's
//! pair heap holds a few hundred thousand entries; profiling showed ~45 % of
//! the loop in `BinaryHeap::pop`). With four children per node and 16-byte
//! entries, the children of a node share one 64-byte cache line and the tree
//! is half as deep.
//!
//! Also [`Buckets`], which orders each contraction pass: a counting pass on
//! the top bits of the cost, then a sort per bucket, done only for the
//! buckets the pass reaches (one comparison sort of all the pass's pairs
//! was a quarter of all instructions on the bunny; an LSD radix sort
//! needed a second buffer).
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

/// Items moved into cost buckets (a counting pass on a coarse key), each
/// bucket sorted only when it is needed: a contraction pass reads its list
/// cheapest first and stops at a cost limit, so about half of the list is
/// never read, and never sorted.
#[derive(Clone, Debug, Default)]
pub struct Buckets {
    /// `ends[k]`: one past the last item of bucket `k`.
    ends: Vec<usize>,
    /// Buckets `0..sorted` are sorted.
    sorted: usize,
}

impl Buckets {
    /// The number of buckets: `bucket(item)` must be below this.
    pub const COUNT: usize = 2048;

    /// Move the concatenation of `parts` into `out`, grouped by
    /// `bucket(item)` (items of a lower bucket first; within a bucket in
    /// the parts' order). In parallel: the buckets are split into one
    /// contiguous run per thread, each thread reads every part and writes
    /// its run's items (the result does not depend on the split). No second
    /// buffer besides `out` is needed (unlike an LSD radix sort; peak
    /// memory: the first contraction pass's list is the largest
    /// allocation of a run).
    pub fn scatter<T: Copy + Send + Sync>(
        parts: Vec<Vec<T>>,
        out: &mut Vec<T>,
        bucket: impl Fn(&T) -> usize + Sync,
    ) -> Buckets {
        use rayon::prelude::*;
        let n: usize = parts.iter().map(Vec::len).sum();
        out.clear();
        if out.capacity() / 2 > n {
            // a later pass's list is a fraction of the first's: give the
            // first's back (it stayed resident to the end of the run: 80 MB
            // of the 4.4M-triangle scan's peak)
            *out = Vec::with_capacity(n);
        }
        let Some(&first) = parts.iter().find_map(|p| p.first()) else {
            return Buckets::default();
        };
        let counts = parts
            .par_iter()
            .fold(
                || vec![0usize; Self::COUNT],
                |mut c, part| {
                    for it in part {
                        c[bucket(it)] += 1;
                    }
                    c
                },
            )
            .reduce(
                || vec![0usize; Self::COUNT],
                |mut a, b| {
                    for (x, y) in a.iter_mut().zip(&b) {
                        *x += y;
                    }
                    a
                },
            );
        let mut starts = Vec::with_capacity(Self::COUNT + 1);
        let mut sum = 0;
        for &c in &counts {
            starts.push(sum);
            sum += c;
        }
        starts.push(sum);
        out.resize(n, first);
        // bucket runs of about equal item counts, one per thread
        let threads = rayon::current_num_threads().clamp(1, 64);
        let mut cuts = vec![0usize];
        for k in 1..threads {
            let target = n * k / threads;
            let b = starts.partition_point(|&x| x < target).min(Self::COUNT);
            if b > *cuts.last().unwrap_or(&0) {
                cuts.push(b);
            }
        }
        cuts.push(Self::COUNT);
        let mut runs: Vec<(usize, usize, &mut [T])> = Vec::with_capacity(cuts.len());
        let mut rest = &mut out[..];
        for w in cuts.windows(2) {
            let (head, tail) = rest.split_at_mut(starts[w[1]] - starts[w[0]]);
            runs.push((w[0], w[1], head));
            rest = tail;
        }
        runs.into_par_iter().for_each(|(lo, hi, dst)| {
            let base = starts[lo];
            let mut next: Vec<usize> = starts[lo..hi].iter().map(|&x| x - base).collect();
            for it in parts.iter().flatten() {
                let b = bucket(it);
                if (lo..hi).contains(&b) {
                    let slot = &mut next[b - lo];
                    dst[*slot] = *it;
                    *slot += 1;
                }
            }
        });
        drop(parts);
        starts.remove(0);
        Buckets {
            ends: starts,
            sorted: 0,
        }
    }

    /// `ends()[k]`: one past the last item of bucket `k` (empty when
    /// there are no items).
    pub fn ends(&self) -> &[usize] {
        &self.ends
    }

    /// One past the last item of the sorted prefix.
    pub fn sorted_end(&self) -> usize {
        self.sorted.checked_sub(1).map_or(0, |k| self.ends[k])
    }

    /// Sort (stably, by `key`) every bucket up to the one holding item
    /// `i` (all of them when `i` is past the end), in parallel.
    pub fn sort_through<T: Copy + Send>(
        &mut self,
        items: &mut [T],
        i: usize,
        key: impl Fn(&T) -> u32 + Sync,
    ) {
        let k = self.ends.partition_point(|&e| e <= i);
        self.sort_through_bucket(items, k, key);
    }

    /// Sort (stably, by `key`) buckets `0..=k` (all when `k` is past the
    /// last), in parallel. `key` is the order: its top 11 bits must be the
    /// bucket [`Buckets::scatter`] was given.
    pub fn sort_through_bucket<T: Copy + Send>(
        &mut self,
        items: &mut [T],
        k: usize,
        key: impl Fn(&T) -> u32 + Sync,
    ) {
        use rayon::prelude::*;
        let upto = k.saturating_add(1).min(self.ends.len());
        if upto <= self.sorted {
            return;
        }
        let start = self.sorted_end();
        let mut slices: Vec<&mut [T]> = Vec::with_capacity(upto - self.sorted);
        let mut rest = &mut items[start..];
        let mut at = start;
        for &e in &self.ends[self.sorted..upto] {
            let (head, tail) = rest.split_at_mut(e - at);
            if head.len() > 1 {
                slices.push(head);
            }
            rest = tail;
            at = e;
        }
        if slices.len() == 1 {
            sort_low_bits(slices[0], &key);
        } else {
            slices.into_par_iter().for_each(|s| sort_low_bits(s, &key));
        }
        self.sorted = upto;
    }
}

/// Stable sort of one bucket by the low 21 bits of `key` (the top 11 are
/// the bucket's): an LSD radix sort, 7 bits a pass, or an insertion sort
/// when short. (A comparison sort of the buckets was 27M instructions of a
/// bunny run.)
fn sort_low_bits<T: Copy>(s: &mut [T], key: &impl Fn(&T) -> u32) {
    if s.len() <= 32 {
        for i in 1..s.len() {
            let x = s[i];
            let kx = key(&x) & LOW_BITS;
            let mut j = i;
            while j > 0 && key(&s[j - 1]) & LOW_BITS > kx {
                s[j] = s[j - 1];
                j -= 1;
            }
            s[j] = x;
        }
        return;
    }
    let mut buf: Vec<T> = s.to_vec();
    for shift in [0, 7, 14] {
        let digit = |x: &T| (key(x) >> shift & 0x7f) as usize;
        let mut start = [0usize; 129];
        for x in s.iter() {
            start[digit(x) + 1] += 1;
        }
        if start.contains(&s.len()) {
            continue; // one digit for all: this pass would not move anything
        }
        for d in 0..128 {
            start[d + 1] += start[d];
        }
        for x in s.iter() {
            let slot = &mut start[digit(x)];
            buf[*slot] = *x;
            *slot += 1;
        }
        s.copy_from_slice(&buf);
    }
}

/// The bits of an order key below its bucket.
const LOW_BITS: u32 = (1 << 21) - 1;

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
        fn buckets_sort(v in prop::collection::vec((any::<f32>(), any::<u16>()), 0..3000), split in 0usize..3000,
                        narrow in any::<bool>()) {
            // (narrow: costs from a few values, so that buckets are long and
            // ties are many: the order within a tie is the input's)
            let v: Vec<(f32, u16)> = if narrow {
                v.iter().map(|&(c, i)| (f32::from(c.to_bits() as u8 % 5) * 0.25, i)).collect()
            } else {
                v
            };
            let order = |x: &(f32, u16)| {
                let b = x.0.to_bits();
                if b >> 31 == 1 { !b } else { b | 0x8000_0000 }
            };
            let key = |x: &(f32, u16)| (order(x) >> 21) as usize;
            let mut expected = v.clone();
            expected.sort_by_key(order);
            let bits = |w: &[(f32, u16)]| w.iter().map(|x| (x.0.to_bits(), x.1)).collect::<Vec<_>>();
            let cut = split.min(v.len());
            let parts = vec![v[..cut].to_vec(), v[cut..].to_vec()];
            let mut got = Vec::new();
            let mut b = Buckets::scatter(parts, &mut got, key);
            // a prefix first, then the rest
            let mid = got.len() / 3;
            b.sort_through(&mut got, mid, order);
            prop_assert!(b.sorted_end() > mid || got.is_empty());
            let mut sorted = got[..b.sorted_end()].to_vec();
            sorted.sort_by_key(order);
            prop_assert_eq!(bits(&got[..b.sorted_end()]), bits(&sorted));
            b.sort_through(&mut got, usize::MAX, order);
            prop_assert_eq!(b.sorted_end(), got.len());
            prop_assert_eq!(bits(&got), bits(&expected));
        }
    }
}
