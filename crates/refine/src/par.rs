//! Data parallelism of the O(N) passes over the refined vertices: the closed-form and streaming
//! interpolations ([`crate::uniform`], [`crate::fast`]), the k-level split of the knots, the
//! knot update ([`update_knots`]) and the certificate's pass ([`crate::certify`]).
//!
//! Work is cut into chunks of a fixed number of units (spans or vertices, about
//! [`CHUNK_VERTICES`] vertices each) that do not depend on the number of threads, each chunk is
//! computed exactly as the sequential loop would compute it, and per-chunk results (sums,
//! maxima, the first non-finite value) are combined in chunk order. So every result is the same
//! bit for bit on one thread or many (tested: `tests/threads.rs` runs a solve in a one-thread
//! pool and in the default pool). The knot update's running sums are those of the chunks
//! ([`update_knots`]): the same on any number of threads, not the bits of one loop.
//!
//! The chunks run on rayon's pool: the global one (as many threads as cores, or
//! `RAYON_NUM_THREADS`), or the pool a caller installs (the Python package's `refine_many`
//! solves many problems on its pool; a solve inside it then splits its chunks over the same
//! workers instead of oversubscribing). On wasm32 (no threads) the chunks run in order on the
//! calling thread.
//!
//! Why: at N = 8·10⁵ vertices (n = 10⁵, k = 7) the certified interpolation is a few passes over
//! ~20 MB of fresh memory — writing the points and the knots, reading them for the certificate —
//! and bound by memory traffic and page faults, which a second core shares.

use std::ops::Range;

use divdiff::Points;

/// About how many vertices one chunk covers: 16 Ki vertices of d = 2 are 256 KiB of output,
/// a core's L2 share, and at N = 8·10⁵ that is ~50 chunks, enough to balance two to eight
/// threads; below it a problem runs as one chunk (no pool round trip for small solves).
pub(crate) const CHUNK_VERTICES: usize = 1 << 14;

/// `f` applied to each item, in parallel, results in the items' order.
pub(crate) fn map<I: Send, T: Send>(items: Vec<I>, f: impl Fn(I) -> T + Sync + Send) -> Vec<T> {
    #[cfg(not(target_arch = "wasm32"))]
    {
        use rayon::prelude::*;
        if items.len() > 1 {
            return items.into_par_iter().map(f).collect();
        }
    }
    items.into_iter().map(f).collect()
}

/// `f(state, b)` for the blocks b = 0 … `count` − 1, in order, split into two vectors: in
/// parallel runs of at least `per_run` blocks, each run with a `state` from `init` (scratch
/// reused block after block), the pairs written straight into the two results' memory (rayon's
/// `unzip_into_vecs`: no zeroing pass first; zeroing a knot update's span tables was ~2 % of the
/// default three updates at n = 10⁵, k = 7). Each block is its own computation, so the result
/// is the same bit for bit on any number of threads. The second vector has room for `reserve`
/// items more (for the caller to append without moving it).
pub(crate) fn unzip_blocks<S, A: Send, B: Send>(
    count: usize,
    per_run: usize,
    reserve: usize,
    init: impl Fn() -> S + Sync + Send,
    f: impl Fn(&mut S, usize) -> (A, B) + Sync + Send,
) -> (Vec<A>, Vec<B>) {
    let (mut a, mut b) = (Vec::new(), Vec::with_capacity(count + reserve));
    #[cfg(not(target_arch = "wasm32"))]
    if count > per_run {
        use rayon::prelude::*;
        (0..count)
            .into_par_iter()
            .with_min_len(per_run.max(1))
            .map_init(init, f)
            .unzip_into_vecs(&mut a, &mut b);
        return (a, b);
    }
    let _ = per_run;
    a.reserve_exact(count);
    let mut state = init();
    for block in 0..count {
        let (x, y) = f(&mut state, block);
        a.push(x);
        b.push(y);
    }
    (a, b)
}

/// `a` and `b` over `vertices` refined vertices: side by side on the pool (`rayon::join`: each
/// may split its own chunks further) when they span more than one chunk — the size from which
/// `Problem::solve` runs on the pool — else (and on wasm32) one after the other, so that a small
/// solve makes no round trip to the pool for microseconds of work.
pub(crate) fn join<A: Send, B: Send>(
    vertices: usize,
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B + Send,
) -> (A, B) {
    #[cfg(not(target_arch = "wasm32"))]
    if vertices > CHUNK_VERTICES {
        return rayon::join(a, b);
    }
    let _ = vertices;
    (a(), b())
}

/// Runs `op` compiled for the widest vector instructions this processor has, chosen at run time
/// (pulp's dispatch: AVX2 on an x86-64 that has it, the target's baseline otherwise), so that
/// a pass's straight loops over the vertices run four doubles at a time instead of SSE2's two.
/// Only code inlined into `op`'s `with_simd` gets the wider instructions, so it and the kernels
/// it calls are `#[inline(always)]` (a closure would be inlined or not at the compiler's whim).
/// The same bits either way: the loops keep their order of operations, and Rust does not fuse
/// a·b + c into one rounding unless the code calls `mul_add`.
///
/// Used where it was measured to pay (the noisy star, closed, N = 8·10⁵, minima of 30 solves in
/// paired runs on two cores): the certificate's sweep (its pass 4.5–5.1 ms → 3.4–3.7 ms), the
/// closed form's table of data rows (`uniform::data_alphas`, square roots and divisions four
/// at a time), and for the knot updates the streaming condensation's span factors
/// (`fast::SpanBlock`: eight spans side by side; three updates on one thread 273 → 175 ms) and
/// the distances of the parametrization ([`parametrize`]). The closed form's spans and the knot
/// split (then units of [`fill_units`], now of [`collect_units`]) were tried and gained nothing:
/// their loops are a span long.
#[inline(always)]
pub(crate) fn vectorized<Op: pulp::WithSimd>(op: Op) -> Op::Output {
    pulp::Arch::new().dispatch(op)
}

/// Runs `f` on a thread of the pool and waits for it: a solve whose passes run in parallel
/// then forks each pass from a worker, which takes part in it, instead of waking the pool from
/// outside and sleeping once per pass (measured at N = 8·10⁵: 20–22 → 17 ms, median of 40). A
/// call already on the pool (the Python package's `refine_many`) runs `f` in place; on wasm32
/// `f` runs on the calling thread.
pub(crate) fn on_pool<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    #[cfg(not(target_arch = "wasm32"))]
    {
        rayon::scope(|_| f())
    }
    #[cfg(target_arch = "wasm32")]
    {
        f()
    }
}

/// The ranges of `len` units in chunks of `per_chunk` units (at least one unit each).
pub(crate) fn ranges(len: usize, per_chunk: usize) -> Vec<Range<usize>> {
    let per_chunk = per_chunk.max(1);
    (0..len.div_ceil(per_chunk))
        .map(|c| c * per_chunk..((c + 1) * per_chunk).min(len))
        .collect()
}

/// The rows of a band system with one off-diagonal — its diagonal, off-diagonal and right-hand
/// side of `d` columns (row-major) — each written by `row(j, diagonal, off-diagonal, rhs row)`
/// for its index j, in parallel chunks of rows standing for `vertices_per_row` vertices each
/// ([`units_per_chunk`]). Each row is its own formula, so every row is the same bit for bit on
/// any number of threads.
pub(crate) fn band_rows(
    diag: &mut [f64],
    off: &mut [[f64; 1]],
    rhs: &mut [f64],
    d: usize,
    vertices_per_row: usize,
    row: impl Fn(usize, &mut f64, &mut f64, &mut [f64]) + Sync + Send,
) {
    let per = units_per_chunk(vertices_per_row);
    let chunks: Vec<_> = diag
        .chunks_mut(per)
        .zip(off.chunks_mut(per))
        .zip(rhs.chunks_mut(per * d))
        .enumerate()
        .collect();
    map(chunks, |(chunk, ((diag, off), rhs))| {
        for (l, ((dg, of), r)) in diag
            .iter_mut()
            .zip(off.iter_mut())
            .zip(rhs.chunks_exact_mut(d))
            .enumerate()
        {
            row(chunk * per + l, dg, &mut of[0], r);
        }
    });
}

/// Units per chunk for units of `vertices_per_unit` vertices each.
pub(crate) fn units_per_chunk(vertices_per_unit: usize) -> usize {
    (CHUNK_VERTICES / vertices_per_unit.max(1)).max(1)
}

/// Fills `out` in units of `unit_len` values (the last unit may be shorter):
/// `fill(state, unit, values)` writes unit `unit`, with one `state` per chunk from `init`
/// (scratch buffers reused unit after unit), chunks of about [`CHUNK_VERTICES`] units' worth of
/// `vertices_per_unit` in parallel. Returns the position of the first non-finite value written,
/// found while each chunk is in cache.
pub(crate) fn fill_units<S>(
    out: &mut [f64],
    unit_len: usize,
    vertices_per_unit: usize,
    init: impl Fn() -> S + Sync + Send,
    fill: impl Fn(&mut S, usize, &mut [f64]) + Sync + Send,
) -> Option<usize> {
    let unit_len = unit_len.max(1);
    let per_chunk = units_per_chunk(vertices_per_unit);
    let chunk_len = per_chunk * unit_len;
    let chunks: Vec<(usize, &mut [f64])> = out.chunks_mut(chunk_len).enumerate().collect();
    let bad = map(chunks, |(c, out)| {
        let mut state = init();
        for (j, unit) in out.chunks_mut(unit_len).enumerate() {
            fill(&mut state, c * per_chunk + j, unit);
        }
        // (A branch-free scan first: the position is wanted only on failure.)
        let bad = out.iter().fold(false, |b, x| b | !x.is_finite());
        bad.then(|| out.iter().position(|x| !x.is_finite()))
            .flatten()
            .map(|k| c * chunk_len + k)
    });
    bad.into_iter().flatten().next()
}

/// What [`collect_units`] collects: `len` values in units of `per_unit` positions (the last
/// unit may be shorter), unit `u`'s value at position `j` being `value(&head(u), j)` — the head
/// (a span's end points, its step) computed once per unit.
pub(crate) struct Units<H, V, B> {
    /// The number of values.
    pub len: usize,
    /// Positions per unit (at least 1).
    pub per_unit: usize,
    /// What a unit's values share.
    pub head: H,
    /// A value from its unit's head and its position in the unit.
    pub value: V,
    /// Whether a value is to be refused (a non-finite coordinate): found while it is written.
    pub bad: B,
}

/// The values of `units`, in order, collected in parallel chunks of about [`CHUNK_VERTICES`]
/// values straight into the result's memory: rayon writes the vector's spare capacity, so there
/// is no zeroing pass before the values are written. (Zeroing the points and the knots of a
/// certified 10⁵-point interpolation before writing them was 8 % of its time on memory the
/// allocator reuses, solve after solve.) Each value is its own formula, so the result is the
/// same bit for bit on any number of threads. Returns the position of the first value `bad`
/// marks, if any.
pub(crate) fn collect_units<Hd, T: Send>(
    units: Units<
        impl Fn(usize) -> Hd + Sync + Send,
        impl Fn(&Hd, usize) -> T + Sync + Send,
        impl Fn(&T) -> bool + Sync + Send,
    >,
) -> Result<Vec<T>, usize> {
    let units = Units {
        per_unit: units.per_unit.max(1),
        ..units
    };
    let flag = std::sync::atomic::AtomicBool::new(false);
    let whole = 0..units.len;
    let mut out = Vec::new();
    #[cfg(not(target_arch = "wasm32"))]
    if units.len > CHUNK_VERTICES {
        use rayon::iter::IndexedParallelIterator;
        unit_iter::UnitPar {
            gen: &units,
            range: whole.clone(),
            flag: &flag,
        }
        .collect_into_vec(&mut out);
    }
    if out.is_empty() {
        out.reserve_exact(units.len);
        out.extend(unit_iter::UnitIter::new(&units, whole, &flag));
    }
    if flag.into_inner() {
        return Err(out.iter().position(&units.bad).expect("a value marked bad"));
    }
    Ok(out)
}

/// The iterator and, off wasm32, the parallel iterator of [`collect_units`] (rayon's plumbing:
/// a producer splits a range of positions, its iterator walks them unit by unit).
mod unit_iter {
    use std::ops::Range;
    use std::sync::atomic::{AtomicBool, Ordering};

    use super::Units;

    /// [`Units`] as one bound: its closures' types behind associated types.
    pub(super) trait Gen: Sync {
        type Head;
        type Item: Send;
        fn per_unit(&self) -> usize;
        fn head(&self, unit: usize) -> Self::Head;
        fn value(&self, head: &Self::Head, j: usize) -> Self::Item;
        fn bad(&self, value: &Self::Item) -> bool;
    }

    impl<Hd, T, H, V, B> Gen for Units<H, V, B>
    where
        T: Send,
        H: Fn(usize) -> Hd + Sync,
        V: Fn(&Hd, usize) -> T + Sync,
        B: Fn(&T) -> bool + Sync,
    {
        type Head = Hd;
        type Item = T;
        fn per_unit(&self) -> usize {
            self.per_unit
        }
        fn head(&self, unit: usize) -> Hd {
            (self.head)(unit)
        }
        fn value(&self, head: &Hd, j: usize) -> T {
            (self.value)(head, j)
        }
        fn bad(&self, value: &T) -> bool {
            (self.bad)(value)
        }
    }

    /// The values at positions `pos .. end`, the head of the current unit kept.
    pub(super) struct UnitIter<'a, G: Gen> {
        gen: &'a G,
        pos: usize,
        end: usize,
        unit: usize,
        j: usize,
        head: Option<G::Head>,
        bad: bool,
        flag: &'a AtomicBool,
    }

    impl<'a, G: Gen> UnitIter<'a, G> {
        pub(super) fn new(gen: &'a G, range: Range<usize>, flag: &'a AtomicBool) -> Self {
            let (unit, j) = (range.start / gen.per_unit(), range.start % gen.per_unit());
            UnitIter {
                gen,
                pos: range.start,
                end: range.end,
                unit,
                j,
                head: (range.start < range.end).then(|| gen.head(unit)),
                bad: false,
                flag,
            }
        }
    }

    impl<G: Gen> Iterator for UnitIter<'_, G> {
        type Item = G::Item;

        #[inline]
        fn next(&mut self) -> Option<G::Item> {
            if self.pos >= self.end {
                return None;
            }
            if self.j == self.gen.per_unit() {
                self.unit += 1;
                self.j = 0;
                self.head = Some(self.gen.head(self.unit));
            }
            let v = self.gen.value(self.head.as_ref()?, self.j);
            self.bad |= self.gen.bad(&v);
            self.j += 1;
            self.pos += 1;
            Some(v)
        }

        fn size_hint(&self) -> (usize, Option<usize>) {
            let left = self.end.saturating_sub(self.pos);
            (left, Some(left))
        }
    }

    impl<G: Gen> DoubleEndedIterator for UnitIter<'_, G> {
        /// (Rayon's collect walks forwards; this is the trait's other end, each value with its
        /// own head.)
        fn next_back(&mut self) -> Option<G::Item> {
            if self.pos >= self.end {
                return None;
            }
            self.end -= 1;
            let head = self.gen.head(self.end / self.gen.per_unit());
            let v = self.gen.value(&head, self.end % self.gen.per_unit());
            self.bad |= self.gen.bad(&v);
            Some(v)
        }
    }

    impl<G: Gen> ExactSizeIterator for UnitIter<'_, G> {}

    impl<G: Gen> Drop for UnitIter<'_, G> {
        fn drop(&mut self) {
            if self.bad {
                self.flag.store(true, Ordering::Relaxed);
            }
        }
    }

    /// The positions `range` of [`collect_units`] as rayon's indexed parallel iterator; it is
    /// also its own producer, split at any position.
    #[cfg(not(target_arch = "wasm32"))]
    pub(super) struct UnitPar<'a, G> {
        pub gen: &'a G,
        pub range: Range<usize>,
        pub flag: &'a AtomicBool,
    }

    #[cfg(not(target_arch = "wasm32"))]
    mod parallel {
        use rayon::iter::plumbing::{
            bridge, Consumer, Producer, ProducerCallback, UnindexedConsumer,
        };
        use rayon::iter::{IndexedParallelIterator, ParallelIterator};

        use super::{Gen, UnitIter, UnitPar};

        impl<'a, G: Gen> Producer for UnitPar<'a, G> {
            type Item = G::Item;
            type IntoIter = UnitIter<'a, G>;

            fn into_iter(self) -> Self::IntoIter {
                UnitIter::new(self.gen, self.range, self.flag)
            }

            fn min_len(&self) -> usize {
                super::super::CHUNK_VERTICES
            }

            fn split_at(self, index: usize) -> (Self, Self) {
                let mid = self.range.start + index;
                (
                    UnitPar {
                        range: self.range.start..mid,
                        ..self
                    },
                    UnitPar {
                        range: mid..self.range.end,
                        ..self
                    },
                )
            }
        }

        impl<G: Gen> ParallelIterator for UnitPar<'_, G> {
            type Item = G::Item;

            fn drive_unindexed<C: UnindexedConsumer<G::Item>>(self, consumer: C) -> C::Result {
                bridge(self, consumer)
            }

            fn opt_len(&self) -> Option<usize> {
                Some(self.range.len())
            }
        }

        impl<G: Gen> IndexedParallelIterator for UnitPar<'_, G> {
            fn len(&self) -> usize {
                self.range.len()
            }

            fn drive<C: Consumer<G::Item>>(self, consumer: C) -> C::Result {
                bridge(self, consumer)
            }

            fn with_producer<CB: ProducerCallback<G::Item>>(self, callback: CB) -> CB::Output {
                callback.callback(self)
            }
        }
    }
}

/// Points of `dim` coordinates written in units of `per_unit` points by [`fill_units`], in
/// place into the result: `recycled` when it has their number and dimension (`fill` writes
/// every coordinate of its unit), else new points zeroed by the allocator first
/// ([`collect_units`] spares that where a value can be computed alone).
///
/// # Errors
/// [`divdiff::Error::NonFinite`] naming the first point with a non-finite coordinate.
pub(crate) fn points_by_units<S>(
    dim: usize,
    len: usize,
    recycled: Option<Points>,
    per_unit: usize,
    init: impl Fn() -> S + Sync + Send,
    fill: impl Fn(&mut S, usize, &mut [f64]) + Sync + Send,
) -> Result<Points, divdiff::Error> {
    let dim = dim.max(1);
    let mut points = match recycled {
        Some(p) if p.len() == len && p.dim() == dim => p,
        _ => Points::zeros(len, dim),
    };
    match fill_units(points.coords_mut(), per_unit * dim, per_unit, init, fill) {
        Some(k) => Err(divdiff::Error::NonFinite {
            field: "points",
            index: k / dim,
        }),
        None => Ok(points),
    }
}

/// [`divdiff::parametrize`] with the span lengths |p_{j+1} − p_j|^e computed in parallel chunks
/// (two square roots per span: a sixth of a knot update at N = 8·10⁵ on one thread) and summed
/// in order: the same knots, bit for bit, and the first failing span's error.
///
/// # Errors
/// As [`divdiff::parametrize`].
pub(crate) fn parametrize(
    points: &Points,
    topology: divdiff::Topology,
    parametrization: divdiff::Parametrization,
) -> Result<divdiff::Knots, divdiff::Error> {
    let spans = divdiff::span_count(points, topology)?;
    if spans <= CHUNK_VERTICES {
        return divdiff::parametrize(points, topology, parametrization);
    }
    let mut t = vec![0.0; spans + 1];
    span_chunks(&mut t[1..], points, parametrization, |_| ())?;
    divdiff::accumulate(&mut t);
    divdiff::Knots::new(topology, t)
}

/// Algorithm 4.1's knot update in place: `knots` (open or closed, from a to b) become the
/// running sums u_j of the spans |p_{j+1} − p_j|^e of `points` (u_0 = 0), mapped affinely back
/// onto [a, b] — t_j = a + u_j (b − a)/u_N, the ends exactly — as [`parametrize`] then
/// [`rescale`] give them, in one parallel pass after the spans and with the old knots' buffer
/// reused (the same length: the same points and topology).
///
/// Beyond one chunk each chunk sums its own spans from zero while they are in cache, and adds
/// the sum of the chunks' totals before it, in order: the running sums of fixed chunks, the same
/// bits on any number of threads, equal to the one-loop sums of [`parametrize`] to rounding
/// (and closer to compensated sums than those: tested). At N = 8·10⁵ the serial running sum, its validation, the
/// mapping and its validation were ~3 ms of each update's ~20 on two threads. Up to one chunk,
/// and on any failure (to report the first bad span or knot as the serial path names it), the
/// result is [`parametrize`] then [`rescale`] exactly.
///
/// # Errors
/// [`KnotUpdateError::Spans`] as [`parametrize`]'s errors; [`KnotUpdateError::Mapped`] as
/// [`rescale`]'s. On error `knots` no longer holds the old knots (the caller refuses the
/// solve).
pub(crate) fn update_knots(
    knots: &mut divdiff::Knots,
    points: &Points,
    parametrization: divdiff::Parametrization,
) -> Result<(), KnotUpdateError> {
    let topology = knots.topology();
    let w = knots.values();
    let (a, b) = (w[0], w[w.len() - 1]);
    let serial = |knots: &mut divdiff::Knots| {
        let u = parametrize(points, topology, parametrization).map_err(KnotUpdateError::Spans)?;
        *knots = rescale(u, a, b).map_err(KnotUpdateError::Mapped)?;
        Ok(())
    };
    let spans = divdiff::span_count(points, topology).map_err(KnotUpdateError::Spans)?;
    if spans <= CHUNK_VERTICES || w.len() != spans + 1 {
        return serial(knots);
    }
    // The old buffer, swapped out for a placeholder (a failure below recomputes serially).
    let placeholder = divdiff::Knots::new(topology, vec![0.0, 1.0, 2.0, 3.0])
        .expect("four increasing knots are valid");
    let old = std::mem::replace(knots, placeholder);
    let mut t = old.into_values();
    // Each chunk: its spans, then their running sums from zero; its total.
    let totals = span_chunks(&mut t[1..], points, parametrization, |out| {
        divdiff::accumulate(out);
        out[out.len() - 1]
    });
    let Ok(totals) = totals else {
        return serial(knots);
    };
    // The offset of each chunk: the totals before it, summed in order; u_N last.
    let mut offsets = Vec::with_capacity(totals.len());
    let mut sum = 0.0;
    for total in totals {
        offsets.push(sum);
        sum += total;
    }
    let ratio = (b - a) / sum;
    let chunks: Vec<(f64, &mut [f64])> = t[1..]
        .chunks_mut(CHUNK_VERTICES)
        .zip(offsets)
        .map(|(out, offset)| (offset, out))
        .collect();
    map(chunks, |(offset, out)| {
        for x in out.iter_mut() {
            *x = a + (offset + *x) * ratio;
        }
    });
    t[0] = a;
    let last = t.len() - 1;
    t[last] = b;
    match divdiff::Knots::new(topology, t) {
        Ok(k) => {
            *knots = k;
            Ok(())
        }
        Err(_) => serial(knots),
    }
}

/// Why [`update_knots`] failed: the knots of the refined points, or their mapping back.
#[derive(Debug)]
pub(crate) enum KnotUpdateError {
    /// As [`parametrize`]'s error (a vanishing span, an exponent whose powers over- or
    /// underflow).
    Spans(divdiff::Error),
    /// As [`rescale`]'s error (the mapped knots not increasing).
    Mapped(divdiff::Error),
}

/// The knots `t` (from t_0 to t_N) mapped affinely onto [a, b]: a + (t_j − t_0)(b − a)/(t_N − t_0),
/// the ends exactly (rounding of the ratio must not move the span), in place.
///
/// # Errors
/// As [`divdiff::Knots::new`]: the mapped knots not increasing or not finite.
pub(crate) fn rescale(t: divdiff::Knots, a: f64, b: f64) -> Result<divdiff::Knots, divdiff::Error> {
    let topology = t.topology();
    let mut out = t.into_values(); // mapped in place: no second N-sized buffer per update
    let (t0, tn) = (out[0], out[out.len() - 1]);
    let ratio = (b - a) / (tn - t0);
    for x in &mut out {
        *x = a + (*x - t0) * ratio;
    }
    out[0] = a;
    let last = out.len() - 1;
    out[last] = b;
    divdiff::Knots::new(topology, out)
}

/// The spans |p_{j+1} − p_j|^e of `points` into `out` (span j at `out[j]`), in parallel chunks
/// of [`CHUNK_VERTICES`], each chunk then handed to `then` while it is in cache: its results in
/// chunk order, or the first failing span's error.
fn span_chunks<T: Send>(
    out: &mut [f64],
    points: &Points,
    parametrization: divdiff::Parametrization,
    then: impl Fn(&mut [f64]) -> T + Sync + Send,
) -> Result<Vec<T>, divdiff::Error> {
    let chunks: Vec<(usize, &mut [f64])> = out
        .chunks_mut(CHUNK_VERTICES)
        .enumerate()
        .map(|(c, out)| (c * CHUNK_VERTICES, out))
        .collect();
    map(chunks, |(first, out)| {
        vectorized(SpanPowers {
            points,
            parametrization,
            first,
            out: &mut *out,
        })?;
        Ok(then(out))
    })
    .into_iter()
    .collect()
}

/// One chunk of [`parametrize`]: [`divdiff::span_powers`] (inlined always) as [`vectorized`]
/// runs it — its distances four at a time and its square roots in vectors.
struct SpanPowers<'a> {
    points: &'a Points,
    parametrization: divdiff::Parametrization,
    first: usize,
    out: &'a mut [f64],
}

impl pulp::WithSimd for SpanPowers<'_> {
    type Output = Result<(), divdiff::Error>;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> Self::Output {
        divdiff::span_powers(self.points, self.parametrization, self.first, self.out)
    }
}

/// Deterministic numbers in [0, 1) for the unit tests of the chunked passes (an LCG; the
/// integration tests have their own in `tests/`).
#[cfg(test)]
pub(crate) fn uniform_stream(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use divdiff::{Parametrization, Points, Topology};

    /// `collect_units` gives the values of the plain loop over units and positions, in order, on
    /// the serial path (one chunk) and the parallel one (units that straddle the chunks, a
    /// shorter last unit); of the values marked bad it reports the first one's position.
    #[test]
    fn collected_units_are_the_plain_loops() {
        let big = 3 * super::CHUNK_VERTICES + 5;
        for (len, per_unit) in [(1, 1), (100, 7), (big, 7), (big, 1), (big, 40_000)] {
            // Value j of unit u: its position, and a rounded function of the unit's head.
            let units = |bad: Vec<usize>| super::Units {
                len,
                per_unit,
                head: move |u: usize| ((u * per_unit) as f64, (u as f64 + 0.5).sqrt()),
                value: |&(start, root): &(f64, f64), j: usize| {
                    [start + j as f64, root / (j as f64 + 3.0)]
                },
                bad: move |v: &[f64; 2]| bad.contains(&(v[0] as usize)),
            };
            let plain: Vec<[f64; 2]> = (0..len)
                .map(|v| {
                    let (u, j) = (v / per_unit, v % per_unit);
                    [v as f64, (u as f64 + 0.5).sqrt() / (j as f64 + 3.0)]
                })
                .collect();
            let got = super::collect_units(units(vec![])).unwrap();
            let bits =
                |x: &[[f64; 2]]| -> Vec<u64> { x.iter().flatten().map(|x| x.to_bits()).collect() };
            assert_eq!(bits(&got), bits(&plain), "len {len}, {per_unit} per unit");
            let marked = vec![len - 1, len / 2, len / 3 + 1];
            let first = *marked.iter().min().unwrap();
            assert_eq!(super::collect_units(units(marked)), Err(first));
        }
    }

    /// The chunked parametrization is divdiff's, bit for bit, open and closed, for the exponents
    /// with and without a general power; a coincident pair in a later chunk is the error of the
    /// first such pair.
    /// The knot update in chunks against the serial one (`parametrize` then `rescale`): within
    /// a few ulps of the span's end beyond one chunk (the running sums are of fixed chunks),
    /// the same bits up to one chunk, the ends exactly, and the serial path's errors.
    #[test]
    fn knot_update_in_chunks_is_the_serial_update() {
        let serial = |p: &Points, topology: Topology, param, a: f64, b: f64| {
            super::rescale(super::parametrize(p, topology, param).unwrap(), a, b).unwrap()
        };
        let mut unif = super::uniform_stream(23);
        for n in [1_000, 3 * super::CHUNK_VERTICES + 101] {
            let x: Vec<f64> = (0..2 * n).map(|_| unif() - 0.5).collect();
            let p = Points::new(2, x).unwrap();
            for topology in [Topology::Open, Topology::Closed] {
                for param in [Parametrization::Centripetal, Parametrization::Exponent(0.7)] {
                    let (a, b) = (-1.25, 3.5);
                    let len = divdiff::span_count(&p, topology).unwrap() + 1;
                    // Old knots on [a, b] (their interior values do not matter).
                    let old: Vec<f64> = (0..len)
                        .map(|j| a + (b - a) * j as f64 / (len - 1) as f64)
                        .collect();
                    let mut knots = divdiff::Knots::new(topology, old).unwrap();
                    super::update_knots(&mut knots, &p, param).unwrap();
                    let want = serial(&p, topology, param, a, b);
                    let (ours, theirs) = (knots.values(), want.values());
                    assert_eq!(ours.len(), theirs.len());
                    assert_eq!((ours[0], ours[len - 1]), (a, b));
                    let off = |v: &[f64], w: &[f64]| {
                        v.iter()
                            .zip(w)
                            .map(|(x, y)| (x - y).abs())
                            .fold(0.0, f64::max)
                    };
                    if n <= super::CHUNK_VERTICES {
                        assert!(ours
                            .iter()
                            .zip(theirs)
                            .all(|(x, y)| x.to_bits() == y.to_bits()));
                        continue;
                    }
                    assert!(off(ours, theirs) > 0.0, "the chunks summed as one loop");
                    // Both against compensated running sums (Neumaier; to about an ulp),
                    // mapped the same way: the chunked sums are within their a-priori bound
                    // (a chunk's running sum plus the offsets' sum, (C + chunks)·ε relative)
                    // and no farther than the one loop's.
                    let mut spans = vec![0.0; len - 1];
                    divdiff::span_powers(&p, param, 0, &mut spans).unwrap();
                    let (mut sum, mut carry) = (0.0f64, 0.0f64);
                    let mut exact = vec![0.0];
                    for x in spans {
                        let t = sum + x;
                        carry += if sum.abs() >= x.abs() {
                            (sum - t) + x
                        } else {
                            (x - t) + sum
                        };
                        sum = t;
                        exact.push(sum + carry);
                    }
                    let total = exact[len - 1];
                    let exact: Vec<f64> = exact.iter().map(|u| a + u * ((b - a) / total)).collect();
                    let chunks = (len / super::CHUNK_VERTICES + 1) as f64;
                    let bound =
                        (super::CHUNK_VERTICES as f64 + chunks + 4.0) * f64::EPSILON * (b - a);
                    let (ours_err, theirs_err) = (off(ours, &exact), off(theirs, &exact));
                    assert!(ours_err <= bound, "{ours_err:e} > {bound:e}");
                    assert!(
                        ours_err <= theirs_err + 4.0 * f64::EPSILON * (b - a),
                        "{ours_err:e} against the one loop's {theirs_err:e}"
                    );
                }
            }
        }
        // A vanishing span in the second chunk: the serial path's error, and so its index.
        let n = 2 * super::CHUNK_VERTICES + 5;
        let mut x: Vec<f64> = (0..2 * n).map(|_| unif() - 0.5).collect();
        let i = super::CHUNK_VERTICES + 300;
        x[2 * i + 2] = x[2 * i];
        x[2 * i + 3] = x[2 * i + 1];
        let p = Points::new(2, x).unwrap();
        let mut knots =
            divdiff::Knots::new(Topology::Closed, (0..=n).map(|j| j as f64).collect()).unwrap();
        match super::update_knots(&mut knots, &p, Parametrization::Centripetal) {
            Err(super::KnotUpdateError::Spans(e)) => assert_eq!(
                e,
                divdiff::Error::ZeroLengthSpan {
                    index: i,
                    next: i + 1
                }
            ),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn parametrize_in_chunks_is_divdiffs() {
        let n = 2 * super::CHUNK_VERTICES + 77;
        let mut unif = super::uniform_stream(11);
        let mut x: Vec<f64> = (0..3 * n).map(|_| unif() - 0.5).collect();
        for topology in [Topology::Open, Topology::Closed] {
            for param in [
                Parametrization::Centripetal,
                Parametrization::Chordal,
                Parametrization::Uniform,
                Parametrization::Exponent(0.7),
            ] {
                let p = Points::new(3, x.clone()).unwrap();
                let ours = super::parametrize(&p, topology, param).unwrap();
                let theirs = divdiff::parametrize(&p, topology, param).unwrap();
                assert!(ours
                    .values()
                    .iter()
                    .zip(theirs.values())
                    .all(|(a, b)| a.to_bits() == b.to_bits()));
            }
        }
        // Points 20_000 and 20_001 coincide (the second chunk), and later 30_000 and 30_001.
        for (i, j) in [(20_000, 20_001), (30_000, 30_001)] {
            let (a, b) = x.split_at_mut(3 * j);
            b[..3].copy_from_slice(&a[3 * i..3 * i + 3]);
        }
        let p = Points::new(3, x).unwrap();
        assert_eq!(
            super::parametrize(&p, Topology::Closed, Parametrization::Centripetal),
            Err(divdiff::Error::ZeroLengthSpan {
                index: 20_000,
                next: 20_001
            })
        );
    }
}
