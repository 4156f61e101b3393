//! `energy::System`: O(N) banded / cyclic solves checked against dense nalgebra solves.
//!
//! Reference: the dense matrix K assembled entry by entry from the definition (bands with
//! aliasing entries added, weights, blocks, stencils Lᵀ B L), solved by nalgebra's LU with the
//! fixed vertices eliminated.

use divdiff::{Points, Topology};
use energy::{Error, System};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

/// Small deterministic generator (xorshift64*), so that a proptest seed fixes the whole problem.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
    fn index(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

/// Dense H = AᵀA of Kersey's energy (math.md §1) on random knots with spans in [0.5, 2].
fn hessian_dense(top: Topology, n: usize, rng: &mut Rng) -> DMatrix<f64> {
    let spans = if top == Topology::Closed { n } else { n - 1 };
    let h: Vec<f64> = (0..spans.max(1)).map(|_| rng.range(0.5, 2.0)).collect();
    let hw = |i: isize| h[i.rem_euclid(h.len() as isize) as usize];
    let mut a = DMatrix::<f64>::zeros(n, n);
    let rows: Vec<usize> = match top {
        Topology::Closed => (0..n).collect(),
        Topology::Open => (1..n.saturating_sub(1)).collect(),
    };
    for i in rows {
        let (hm, hp) = (hw(i as isize - 1), hw(i as isize));
        let s = (hm + hp).sqrt();
        let a1 = 2f64.sqrt() / (hm * s);
        let a3 = 2f64.sqrt() / (hp * s);
        let cols = [(i + n - 1) % n, i, (i + 1) % n];
        for (c, v) in cols.iter().zip([a1, -a1 - a3, a3]) {
            a[(i, *c)] += v;
        }
    }
    a.transpose() * a
}

/// Bands (diag, off1, off2) whose aliasing sum reproduces the dense pentadiagonal H.
fn bands_of(top: Topology, h: &DMatrix<f64>) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = h.nrows();
    let diag = (0..n).map(|j| h[(j, j)]).collect();
    let mut off1 = vec![0.0; n];
    let mut off2 = vec![0.0; n];
    for j in 0..n {
        match top {
            Topology::Open => {
                if j + 1 < n {
                    off1[j] = h[(j, j + 1)];
                }
                if j + 2 < n {
                    off2[j] = h[(j, j + 2)];
                }
            }
            Topology::Closed if n == 3 => {
                // K_{j,j+1} = off1[j] + off2[j+1]
                off1[j] = 0.5 * h[(j, (j + 1) % n)];
                off2[j] = 0.5 * h[(j, (j + 2) % n)];
            }
            Topology::Closed if n == 4 => {
                off1[j] = h[(j, (j + 1) % n)];
                off2[j] = 0.5 * h[(j, (j + 2) % n)];
            }
            Topology::Closed => {
                off1[j] = h[(j, (j + 1) % n)];
                off2[j] = h[(j, (j + 2) % n)];
            }
        }
    }
    (diag, off1, off2)
}

/// Dense K ⊗-expanded from the definition of the band convention (aliasing entries add).
fn dense_from_bands(top: Topology, d: &[f64], o1: &[f64], o2: &[f64]) -> DMatrix<f64> {
    let n = d.len();
    let mut k = DMatrix::zeros(n, n);
    for j in 0..n {
        k[(j, j)] += d[j];
        for (band, step) in [(o1, 1), (o2, 2)] {
            if top == Topology::Open && j + step >= n {
                continue;
            }
            let m = (j + step) % n;
            k[(j, m)] += band[j];
            k[(m, j)] += band[j];
        }
    }
    k
}

fn kron(h: &DMatrix<f64>, d: usize) -> DMatrix<f64> {
    let n = h.nrows();
    let mut k = DMatrix::zeros(n * d, n * d);
    for i in 0..n {
        for j in 0..n {
            for c in 0..d {
                k[(i * d + c, j * d + c)] = h[(i, j)];
            }
        }
    }
    k
}

fn random_psd(d: usize, scale: f64, rng: &mut Rng) -> Vec<f64> {
    let c: Vec<f64> = (0..d * d).map(|_| rng.range(-1.0, 1.0)).collect();
    let mut b = vec![0.0; d * d];
    for r in 0..d {
        for s in 0..d {
            b[r * d + s] = scale * (0..d).map(|q| c[r * d + q] * c[s * d + q]).sum::<f64>();
        }
    }
    b
}

struct Problem {
    system: System,
    dense: DMatrix<f64>,
    fixed: Vec<bool>,
}

/// A random system: H on random knots, weights at some vertices, random PSD blocks and
/// stencils (if `coupling`), a random fixed set.
fn random_problem(top: Topology, n: usize, d: usize, coupling: bool, seed: u64) -> Problem {
    let mut rng = Rng(seed.wrapping_mul(2_654_435_761).wrapping_add(12345) | 1);
    let h = hessian_dense(top, n, &mut rng);
    let (dg, o1, o2) = bands_of(top, &h);
    let back = dense_from_bands(top, &dg, &o1, &o2);
    assert!((&back - &h).norm() <= 1e-12 * h.norm().max(1.0));
    let mut sys = System::from_bands(top, dg, o1, o2, d).unwrap();
    let mut k = kron(&h, d);
    let scale = (0..n).map(|j| h[(j, j)]).fold(1.0, f64::max);
    // Weights: every vertex gets a chance; vertex 0 and the last always weighted so K is SPD.
    for j in 0..n {
        if j == 0 || j == n - 1 || rng.next() < 0.3 {
            let w = rng.range(0.1, 1.0) * scale;
            sys.add_weight(j, w).unwrap();
            for c in 0..d {
                k[(j * d + c, j * d + c)] += w;
            }
        }
    }
    if coupling {
        for _ in 0..(n / 2 + 1) {
            let v = rng.index(n);
            let b = random_psd(d, scale * rng.range(0.0, 2.0), &mut rng);
            sys.add_block(v, &b).unwrap();
            for r in 0..d {
                for c in 0..d {
                    k[(v * d + r, v * d + c)] += b[r * d + c];
                }
            }
        }
        for _ in 0..(n / 2 + 1) {
            let len = 1 + rng.index(3);
            let start = rng.index(n);
            let verts: Vec<usize> = (0..len)
                .map(|k| match top {
                    Topology::Closed => (start + k) % n,
                    Topology::Open => (start + k).min(n - 1),
                })
                .collect();
            let mut verts = verts;
            verts.dedup();
            let stencil: Vec<(usize, f64)> =
                verts.iter().map(|&v| (v, rng.range(-2.0, 2.0))).collect();
            let b = random_psd(d, scale * rng.range(0.0, 1.0), &mut rng);
            sys.add_stencil(&stencil, &b).unwrap();
            for &(va, ca) in &stencil {
                for &(vb, cb) in &stencil {
                    for r in 0..d {
                        for c in 0..d {
                            k[(va * d + r, vb * d + c)] += ca * cb * b[r * d + c];
                        }
                    }
                }
            }
        }
    }
    let mut fixed = vec![false; n];
    for (j, f) in fixed.iter_mut().enumerate() {
        if rng.next() < 0.2 && j % 3 == 1 {
            *f = true;
            sys.fix(j).unwrap();
        }
    }
    Problem {
        system: sys,
        dense: k,
        fixed,
    }
}

/// Solves with `System` and densely; returns (relative residual, relative difference).
fn check(p: &Problem, d: usize, seed: u64) -> (f64, f64) {
    let n = p.fixed.len();
    let mut rng = Rng(seed | 7);
    let rhs: Vec<f64> = (0..n * d).map(|_| rng.range(-1.0, 1.0)).collect();
    let x = p
        .system
        .factor()
        .unwrap()
        .solve(&Points::new(d, rhs.clone()).unwrap())
        .unwrap();
    let x = x.coords();
    // Dense: free rows K_FF x_F = b_F − K_FC x_C, x_C = prescribed values.
    let free: Vec<usize> = (0..n * d).filter(|&r| !p.fixed[r / d]).collect();
    let mut kff = DMatrix::zeros(free.len(), free.len());
    let mut b = DVector::zeros(free.len());
    for (a, &r) in free.iter().enumerate() {
        b[a] = rhs[r];
        for (c, rc) in rhs.iter().enumerate() {
            if p.fixed[c / d] {
                b[a] -= p.dense[(r, c)] * rc;
            }
        }
        for (e, &c) in free.iter().enumerate() {
            kff[(a, e)] = p.dense[(r, c)];
        }
    }
    for r in 0..n * d {
        if p.fixed[r / d] {
            assert!((x[r] - rhs[r]).abs() <= 1e-15 * rhs[r].abs().max(1.0));
        }
    }
    let xf = DVector::from_iterator(free.len(), free.iter().map(|&r| x[r]));
    let res = (&kff * &xf - &b).norm() / (kff.norm() * xf.norm() + b.norm()).max(1e-300);
    let xref = kff.clone().lu().solve(&b).unwrap();
    let diff = (&xf - &xref).norm() / xref.norm().max(1e-300);
    (res, diff)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn banded_matches_dense_open(n in 1usize..14, d in 1usize..5, coupling: bool, seed: u64) {
        let p = random_problem(Topology::Open, n, d, coupling, seed);
        let (res, diff) = check(&p, d, seed);
        prop_assert!(res <= 1e-13, "residual {res}");
        prop_assert!(diff <= 1e-8, "difference {diff}");
    }

    #[test]
    fn cyclic_matches_dense_closed(n in 3usize..14, d in 1usize..5, coupling: bool, seed: u64) {
        let p = random_problem(Topology::Closed, n, d, coupling, seed);
        let (res, diff) = check(&p, d, seed);
        prop_assert!(res <= 1e-13, "residual {res}");
        prop_assert!(diff <= 1e-8, "difference {diff}");
    }
}

#[test]
fn apply_matches_dense() {
    for top in [Topology::Open, Topology::Closed] {
        for n in [3, 4, 5, 9] {
            for d in 1..4 {
                let p = random_problem(top, n, d, true, (n * 10 + d) as u64);
                let mut rng = Rng(99);
                let x: Vec<f64> = (0..n * d).map(|_| rng.range(-1.0, 1.0)).collect();
                let y = p.system.apply(&Points::new(d, x.clone()).unwrap()).unwrap();
                let yref = &p.dense * DVector::from_vec(x);
                let err = (DVector::from_column_slice(y.coords()) - &yref).norm();
                assert!(
                    err <= 1e-12 * yref.norm().max(1.0),
                    "{top:?} n={n} d={d}: {err}"
                );
            }
        }
    }
}

fn bare(top: Topology, n: usize, d: usize) -> System {
    let mut rng = Rng(5);
    let h = hessian_dense(top, n, &mut rng);
    let (dg, o1, o2) = bands_of(top, &h);
    System::from_bands(top, dg, o1, o2, d).unwrap()
}

#[test]
fn singular_systems_are_typed_errors() {
    // ker H = linear polynomials (open) / constants (closed): no weights → singular.
    for n in [3, 4, 5, 8, 50, 1000] {
        for d in [1, 2] {
            for top in [Topology::Open, Topology::Closed] {
                let s = bare(top, n, d);
                assert!(
                    matches!(s.factor(), Err(Error::Singular { .. })),
                    "{top:?} n={n} d={d}"
                );
                // The same through the block path.
                let mut s = bare(top, n, d);
                s.add_block(0, &vec![0.0; d * d]).unwrap();
                assert!(
                    matches!(s.factor(), Err(Error::Singular { .. })),
                    "block {top:?} n={n} d={d}"
                );
            }
            // Open: one weight pins the constant but not the slope.
            let mut s = bare(Topology::Open, n, d);
            s.add_weight(n / 2, 1.0).unwrap();
            assert!(
                matches!(s.factor(), Err(Error::Singular { .. })),
                "open n={n}"
            );
            // Closed: one weight suffices.
            let mut s = bare(Topology::Closed, n, d);
            s.add_weight(n / 2, 1.0).unwrap();
            assert!(s.factor().is_ok(), "closed n={n}");
            // Open: two weights suffice.
            let mut s = bare(Topology::Open, n, d);
            s.fix(0).unwrap();
            s.add_weight(n - 1, 1.0).unwrap();
            assert!(s.factor().is_ok(), "open n={n}");
        }
    }
}

#[test]
fn bad_input_is_rejected() {
    let mut s = bare(Topology::Closed, 6, 2);
    assert!(matches!(
        s.add_weight(6, 1.0),
        Err(Error::IndexOutOfRange { .. })
    ));
    assert!(matches!(
        s.add_block(0, &[1.0]),
        Err(Error::WrongLength { .. })
    ));
    assert!(matches!(
        s.add_stencil(&[(0, 1.0), (3, 1.0)], &[1.0, 0.0, 0.0, 1.0]),
        Err(Error::StencilTooWide { .. })
    ));
    assert!(s
        .add_stencil(&[(5, 1.0), (0, -2.0), (1, 1.0)], &[1.0, 0.0, 0.0, 1.0])
        .is_ok());
    assert!(matches!(s.fix(9), Err(Error::IndexOutOfRange { .. })));
    assert!(matches!(
        System::from_bands(
            Topology::Closed,
            vec![1.0; 2],
            vec![0.0; 2],
            vec![0.0; 2],
            1
        ),
        Err(Error::WrongLength { .. })
    ));
    assert!(matches!(
        System::from_bands(Topology::Open, vec![1.0; 4], vec![0.0; 3], vec![0.0; 4], 1),
        Err(Error::WrongLength { .. })
    ));
    s.add_weight(0, 1.0).unwrap();
    let f = s.factor().unwrap();
    assert!(matches!(
        f.solve(&Points::zeros(5, 2)),
        Err(Error::WrongLength { .. })
    ));
}

#[test]
fn large_closed_solve_has_small_residual() {
    // N = 20 000 closed with weights at every 8th vertex: residual of the O(N) solve.
    let n = 20_000;
    let d = 2;
    let mut rng = Rng(3);
    let h: Vec<f64> = (0..n).map(|_| rng.range(0.5, 2.0)).collect();
    let mut a_rows = Vec::new();
    for i in 0..n {
        let (hm, hp) = (h[(i + n - 1) % n], h[i]);
        let s = (hm + hp).sqrt();
        let a1 = 2f64.sqrt() / (hm * s);
        let a3 = 2f64.sqrt() / (hp * s);
        a_rows.push([a1, -a1 - a3, a3]);
    }
    // H = AᵀA bands: row i of A touches (i−1, i, i+1).
    let mut dg = vec![0.0; n];
    let mut o1 = vec![0.0; n];
    let mut o2 = vec![0.0; n];
    for (i, r) in a_rows.iter().enumerate() {
        let c = [(i + n - 1) % n, i, (i + 1) % n];
        for a in 0..3 {
            dg[c[a]] += r[a] * r[a];
        }
        o1[c[0]] += r[0] * r[1];
        o1[c[1]] += r[1] * r[2];
        o2[c[0]] += r[0] * r[2];
    }
    let mut s = System::from_bands(Topology::Closed, dg, o1, o2, d).unwrap();
    for j in (0..n).step_by(8) {
        s.add_weight(j, 1.0).unwrap();
    }
    let b: Vec<f64> = (0..n * d).map(|_| rng.range(-1.0, 1.0)).collect();
    let b = Points::new(d, b).unwrap();
    let x = s.factor().unwrap().solve(&b).unwrap();
    let kx = s.apply(&x).unwrap();
    let r: f64 = kx
        .coords()
        .iter()
        .zip(b.coords())
        .map(|(u, v)| (u - v) * (u - v))
        .sum::<f64>()
        .sqrt();
    let bn: f64 = b.coords().iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(r <= 1e-9 * bn, "residual {r} vs {bn}");
}

#[test]
fn wide_dimensions_and_tiny_closed_curves_take_the_general_paths() {
    // d > 4 takes banded's general block path (d at run time), closed N ≤ 4 an aliased band
    // whose rows are all border.
    for top in [Topology::Open, Topology::Closed] {
        for n in [3, 4, 6, 9] {
            for d in [5, 6] {
                for coupling in [false, true] {
                    let seed = (n * 100 + d * 10) as u64 + u64::from(coupling);
                    let p = random_problem(top, n, d, coupling, seed);
                    let (res, diff) = check(&p, d, seed);
                    assert!(res <= 1e-13, "{top:?} n={n} d={d}: residual {res}");
                    assert!(diff <= 1e-8, "{top:?} n={n} d={d}: difference {diff}");
                }
            }
        }
    }
}

#[test]
fn interpolatory_solution_has_zero_hp_at_free_vertices() {
    // Kersey (3.3): p fixed at every third vertex, (Hp)_j = 0 elsewhere; H from energy::Hessian.
    let mut rng = Rng(17);
    for top in [Topology::Open, Topology::Closed] {
        for n in [4, 7, 30, 301] {
            let count = if top == Topology::Closed { n + 1 } else { n };
            let mut t = vec![0.0];
            for _ in 1..count {
                let last = *t.last().unwrap();
                t.push(last + rng.range(0.2, 2.0));
            }
            let knots = divdiff::Knots::new(top, t).unwrap();
            let h = energy::Hessian::new(&knots);
            let mut fixed: Vec<usize> = (0..n).step_by(3).collect();
            if top == Topology::Open && !fixed.contains(&(n - 1)) {
                fixed.push(n - 1);
            }
            let d = 2;
            let values: Vec<f64> = (0..fixed.len() * d).map(|_| rng.range(-5.0, 5.0)).collect();
            let values = Points::new(d, values).unwrap();
            let p = energy::solve_interpolatory(&h, &fixed, &values).unwrap();
            for (k, &j) in fixed.iter().enumerate() {
                assert_eq!(p.point(j), values.point(k));
            }
            let hp = h.apply(&p);
            let scale = h.max_abs() * p.coords().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for j in (0..n).filter(|j| !fixed.contains(j)) {
                for v in hp.point(j) {
                    assert!(v.abs() <= 1e-11 * scale, "{top:?} n={n}: (Hp)_{j} = {v}");
                }
            }
        }
    }
    // Too little fixed: singular, typed.
    let knots = divdiff::Knots::open((0..6).map(f64::from).collect()).unwrap();
    let h = energy::Hessian::new(&knots);
    let one = Points::new(1, vec![1.0]).unwrap();
    assert!(matches!(
        energy::solve_interpolatory(&h, &[2], &one),
        Err(Error::Singular { .. })
    ));
    let two = Points::new(1, vec![1.0, 2.0]).unwrap();
    assert!(matches!(
        energy::solve_interpolatory(&h, &[2, 2], &two),
        Err(Error::DuplicateFixed { index: 2 })
    ));
}

/// A closed system with coupling blocks long enough for the border rows to decay below the
/// flush threshold (so only the rows near the ends are stored and visited): the block band
/// solve still has a rounding-level residual, checked with the independent `apply`.
#[test]
fn large_closed_block_solve_with_flushed_border_has_small_residual() {
    let n = 6_000;
    let d = 2;
    let mut rng = Rng(17);
    let mut dg = vec![0.0; n];
    let mut o1 = vec![0.0; n];
    let mut o2 = vec![0.0; n];
    // H = AᵀA for second differences (rows touch i−1, i, i+1), well conditioned by the blocks.
    for i in 0..n {
        let r = [1.0, -2.0, 1.0];
        let c = [(i + n - 1) % n, i, (i + 1) % n];
        for a in 0..3 {
            dg[c[a]] += r[a] * r[a];
        }
        o1[c[0]] += r[0] * r[1];
        o1[c[1]] += r[1] * r[2];
        o2[c[0]] += r[0] * r[2];
    }
    let mut s = System::from_bands(Topology::Closed, dg, o1, o2, d).unwrap();
    for j in (0..n).step_by(4) {
        let blk = random_psd(d, 1.0 + 10.0 * rng.next(), &mut rng);
        s.add_block(j, &blk).unwrap();
    }
    s.fix(n / 2).unwrap();
    let b: Vec<f64> = (0..n * d).map(|_| rng.range(-1.0, 1.0)).collect();
    let x = s
        .factor()
        .unwrap()
        .solve(&Points::new(d, b.clone()).unwrap())
        .unwrap();
    let kx = s.apply(&x).unwrap();
    let mut r2 = 0.0;
    let mut b2 = 0.0;
    for v in 0..n {
        if v == n / 2 {
            // The fixed vertex keeps its prescribed value.
            for c in 0..d {
                assert!((x.point(v)[c] - b[v * d + c]).abs() <= 1e-15);
            }
            continue;
        }
        for c in 0..d {
            // The fixed vertex's value enters the free rows as K_vf x_f: part of K x.
            r2 += (kx.point(v)[c] - b[v * d + c]).powi(2);
            b2 += b[v * d + c].powi(2);
        }
    }
    assert!(
        r2.sqrt() <= 1e-10 * b2.sqrt(),
        "residual {} vs {}",
        r2.sqrt(),
        b2.sqrt()
    );
}

/// `apply_flat` equals `apply`, and `clear_blocks` followed by re-adding the same blocks gives
/// the same system (same products, same solutions) as building it afresh.
#[test]
fn apply_flat_and_clear_blocks_match_a_fresh_system() {
    for top in [Topology::Open, Topology::Closed] {
        for (n, d) in [(5, 1), (9, 2), (12, 3), (7, 4), (6, 5)] {
            let p = random_problem(top, n, d, true, (n * 7 + d) as u64);
            let mut rng = Rng(41);
            let x: Vec<f64> = (0..n * d).map(|_| rng.range(-1.0, 1.0)).collect();
            let y = p.system.apply(&Points::new(d, x.clone()).unwrap()).unwrap();
            let mut yf = vec![7.0; n * d];
            p.system.apply_flat(&x, &mut yf).unwrap();
            for (a, b) in y.coords().iter().zip(&yf) {
                assert!(
                    (a - b).abs() <= 1e-15 * (1.0 + a.abs()),
                    "{top:?} n={n} d={d}"
                );
            }
            assert!(p.system.apply_flat(&x[1..], &mut yf).is_err());
            // Blocks on a bare system, cleared, re-added: identical factorization results.
            let mut fresh = bare(top, n, d);
            for v in 0..n {
                fresh.add_weight(v, 1.0).unwrap();
            }
            let mut reused = fresh.clone();
            let blocks: Vec<(usize, Vec<f64>)> = (0..n)
                .step_by(2)
                .map(|v| (v, random_psd(d, 2.0, &mut rng)))
                .collect();
            for (v, _) in &blocks {
                reused.add_block(*v, &random_psd(d, 5.0, &mut rng)).unwrap();
            }
            reused.clear_blocks();
            for (v, blk) in &blocks {
                fresh.add_block(*v, blk).unwrap();
                reused.add_block(*v, blk).unwrap();
            }
            let b = Points::new(d, x.clone()).unwrap();
            let xa = fresh.factor().unwrap().solve(&b).unwrap();
            let xb = reused.factor().unwrap().solve(&b).unwrap();
            for (a, b) in xa.coords().iter().zip(xb.coords()) {
                assert!(
                    (a - b).abs() <= 1e-14 * (1.0 + a.abs()),
                    "{top:?} n={n} d={d}"
                );
            }
        }
    }
}

/// One `Factor` refilled by `factor_into` across systems of both kinds (coupling blocks or
/// not), sizes, dimensions, with and without fixed vertices, and after a failed factorization,
/// solves exactly as a fresh factor of each (bit for bit); a failure leaves it empty (its solves
/// report the wrong length).
#[test]
fn a_refilled_factor_is_a_fresh_one() {
    let mut f = energy::Factor::empty();
    let mut rng = Rng(77);
    let mut seed = 1;
    for top in [Topology::Open, Topology::Closed] {
        for (n, d, coupling) in [
            (9, 2, true),
            (9, 2, false),
            (30, 3, true),
            (5, 1, false),
            (30, 2, true),
        ] {
            seed += 1;
            let p = random_problem(top, n, d, coupling, seed);
            p.system.factor_into(energy::PIVOT_RTOL, &mut f).unwrap();
            let b = Points::new(d, (0..n * d).map(|_| rng.range(-1.0, 1.0)).collect()).unwrap();
            let want = p.system.factor().unwrap().solve(&b).unwrap();
            let got = f.solve(&b).unwrap();
            assert!(
                want.coords()
                    .iter()
                    .zip(got.coords())
                    .all(|(a, c)| a.to_bits() == c.to_bits()),
                "{top:?} n={n} d={d} coupling {coupling}"
            );
            // A singular system (no weights): the error, and an empty factor after it.
            let s = bare(top, n, d);
            assert!(matches!(
                s.factor_into(energy::PIVOT_RTOL, &mut f),
                Err(Error::Singular { .. })
            ));
            assert!(matches!(f.solve(&b), Err(Error::WrongLength { .. })));
        }
    }
}
