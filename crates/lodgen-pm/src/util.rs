//! Small helpers shared by the phases: cache prefetch hints and per-thread
//! vertex marks. Depends on nothing else in the crate.

/// A hint to bring `x`'s cache line in (nothing on targets without one).
#[inline(always)]
pub(crate) fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint to the cache: it reads no value and
    // cannot fault, and `x` is a valid reference anyway.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
            (x as *const T).cast::<i8>(),
        );
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

thread_local! {
    /// Per-thread vertex marks for the legality check (which reads
    /// only, so that the batched walk can run it on several threads):
    /// marks and the last generation handed out.
    static MARKS: std::cell::RefCell<(Vec<u32>, u32)> = const { std::cell::RefCell::new((Vec::new(), 0)) };
}

/// Run `f` with this thread's marks (at least `n` of them) and two fresh
/// generations `g` and `g + 1` no mark holds yet.
pub(crate) fn with_marks<R>(n: usize, f: impl FnOnce(&mut [u32], u32) -> R) -> R {
    MARKS.with(|m| {
        let (mark, last) = &mut *m.borrow_mut();
        if mark.len() < n {
            mark.resize(n, 0);
        }
        if *last >= u32::MAX - 2 {
            mark.fill(0);
            *last = 0;
        }
        let g = *last + 1;
        *last += 2;
        f(mark, g)
    })
}
