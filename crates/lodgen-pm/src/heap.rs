//! A 4-ary min-heap for the contraction loop.
//!
//! `std::collections::BinaryHeap` is binary: a pop walks ~log₂ n levels and
//! each level is a cache miss once the heap outgrows the cache (the bunny's
//! pair heap holds a few hundred thousand entries; profiling showed ~45 % of
//! the loop in `BinaryHeap::pop`). With four children per node and 16-byte
//! entries, the children of a node share one 64-byte cache line and the tree
//! is half as deep.
//!
//! Owns only the ordering container; what an entry means is `collapse`'s.

/// A 4-ary min-heap ordered by `Ord` (smallest first).
#[derive(Clone, Debug, Default)]
pub struct QuadHeap<T> {
    data: Vec<T>,
}

impl<T: Ord + Copy> QuadHeap<T> {
    /// Build from unordered items in O(n).
    pub fn from_vec(data: Vec<T>) -> Self {
        let mut h = QuadHeap { data };
        let n = h.data.len();
        if n > 1 {
            for i in (0..=(n - 2) / 4).rev() {
                h.sift_down(i);
            }
        }
        h
    }

    pub fn len(&self) -> usize {
        self.data.len()
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    pub fn push(&mut self, item: T) {
        self.data.push(item);
        let mut i = self.data.len() - 1;
        while i > 0 {
            let parent = (i - 1) / 4;
            if item < self.data[parent] {
                self.data[i] = self.data[parent];
                i = parent;
            } else {
                break;
            }
        }
        self.data[i] = item;
    }

    pub fn pop(&mut self) -> Option<T> {
        let last = self.data.pop()?;
        if self.data.is_empty() {
            return Some(last);
        }
        let top = self.data[0];
        self.data[0] = last;
        self.sift_down(0);
        Some(top)
    }

    /// Remove every item (in no particular order).
    pub fn drain(&mut self) -> std::vec::Drain<'_, T> {
        self.data.drain(..)
    }

    fn sift_down(&mut self, mut i: usize) {
        let n = self.data.len();
        let item = self.data[i];
        loop {
            let first = 4 * i + 1;
            if first >= n {
                break;
            }
            let end = (first + 4).min(n);
            let mut best = first;
            for c in first + 1..end {
                if self.data[c] < self.data[best] {
                    best = c;
                }
            }
            if self.data[best] < item {
                self.data[i] = self.data[best];
                i = best;
            } else {
                break;
            }
        }
        self.data[i] = item;
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
    }
}
