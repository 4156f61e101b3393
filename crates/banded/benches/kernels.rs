//! Criterion micro-benchmarks of every `banded` kernel (factor and solve separately), and the
//! measurement behind the choice of the bordered form for cyclic matrices: the same cyclic
//! matrix factored and solved bordered (`SymBand<W>` / `BlockBand<W>` cyclic) and in the
//! zig-zag order 0, n−1, 1, n−2, … as an open band of twice the width (`SymBand<2W>` /
//! `BlockBand<2W>` open, with the permutation of the right-hand side included).
//!
//! Run: `cargo bench -p banded` (or `-- <filter>`); sizes n = 10⁵ rows.

use banded::{vector, BlockBand, BlockFactor, FactorOptions, SymBand, SymBandFactor, Topology};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

const N: usize = 100_000;

/// Deterministic values in [−1, 1).
fn wave(k: usize) -> f64 {
    ((k * 7919) % 1000) as f64 / 500.0 - 1.0
}

/// A diagonally dominant symmetric band of half-bandwidth W (the shape of the energy Hessians
/// plus weights and of the condensed data-row systems).
fn scalar<const W: usize>(n: usize, topology: Topology) -> SymBand<W> {
    let diag = (0..n)
        .map(|i| 2.0 * W as f64 + 1.0 + 0.5 * wave(i))
        .collect();
    let off = (0..n)
        .map(|i| std::array::from_fn(|k| 0.9 * wave(i * 31 + k)))
        .collect();
    SymBand::from_bands(topology, diag, off).expect("bands of equal length")
}

/// S ⊗ I_d + a d×d coupling block on every diagonal and every first off-diagonal position.
fn block<const W: usize>(n: usize, d: usize, topology: Topology) -> BlockBand<W> {
    let mut a = BlockBand::from_scalar(scalar::<W>(n, topology), d).expect("d ≥ 1");
    let blk: Vec<f64> = (0..d * d).map(|e| 0.1 * wave(e)).collect();
    let sym: Vec<f64> = (0..d * d)
        .map(|e| if e / d == e % d { 0.5 } else { 0.05 })
        .collect();
    for i in 0..n {
        let j = if i + 1 < n { i + 1 } else { 0 };
        a.add(i, i, &sym).expect("in the band");
        if topology == Topology::Cyclic || i + 1 < n {
            a.add(i, j, &blk).expect("in the band");
        }
    }
    a
}

fn zigzag(n: usize) -> Vec<usize> {
    let half = n.div_ceil(2);
    (0..n)
        .map(|i| if i < half { 2 * i } else { 2 * (n - 1 - i) + 1 })
        .collect()
}

fn scalar_kernels(c: &mut Criterion) {
    let mut g = c.benchmark_group("scalar");
    g.sample_size(10).throughput(Throughput::Elements(N as u64));
    macro_rules! case {
        ($w:literal, $top:expr, $cols:expr) => {{
            let a = scalar::<$w>(N, $top);
            let name = format!("W={} {:?}", $w, $top);
            let mut f = SymBandFactor::default();
            g.bench_function(format!("{name} factor"), |b| {
                b.iter(|| a.factor_into(&FactorOptions::default(), &mut f).unwrap())
            });
            for cols in $cols {
                let x0: Vec<f64> = (0..N * cols).map(wave).collect();
                let mut x = x0.clone();
                g.bench_function(format!("{name} solve {cols} columns"), |b| {
                    b.iter(|| {
                        x.copy_from_slice(&x0);
                        f.solve_in_place(black_box(&mut x), cols).unwrap()
                    })
                });
            }
        }};
    }
    case!(1, Topology::Open, [2]);
    case!(1, Topology::Cyclic, [2]);
    case!(2, Topology::Open, [2]);
    case!(2, Topology::Cyclic, [1, 2, 3]);
    case!(3, Topology::Open, [1]);
    g.finish();
}

fn block_kernels(c: &mut Criterion) {
    let mut g = c.benchmark_group("block");
    g.sample_size(10).throughput(Throughput::Elements(N as u64));
    for d in [2, 3, 5] {
        for top in [Topology::Open, Topology::Cyclic] {
            let a = block::<2>(N, d, top);
            let mut f = BlockFactor::default();
            g.bench_function(format!("W=2 d={d} {top:?} factor"), |b| {
                b.iter(|| a.factor_into(&FactorOptions::default(), &mut f).unwrap())
            });
            let x0: Vec<f64> = (0..N * d).map(wave).collect();
            let mut x = x0.clone();
            g.bench_function(format!("W=2 d={d} {top:?} solve"), |b| {
                b.iter(|| {
                    x.copy_from_slice(&x0);
                    f.solve_in_place(black_box(&mut x), 1).unwrap()
                })
            });
        }
    }
    g.finish();
}

/// Bordered against zig-zag on the same cyclic matrices, factor + solve (+ permutation).
fn cyclic_ordering(c: &mut Criterion) {
    let mut g = c.benchmark_group("cyclic ordering");
    g.sample_size(10).throughput(Throughput::Elements(N as u64));
    let pos = zigzag(N);
    // Scalar tridiagonal, 2 columns.
    let a = scalar::<1>(N, Topology::Cyclic);
    let mut z = SymBand::<2>::zeros(N, Topology::Open);
    for i in 0..N {
        z.add(pos[i], pos[i], a.diag()[i]).unwrap();
        z.add(pos[i], pos[(i + 1) % N], a.off()[i][0]).unwrap();
    }
    let x0: Vec<f64> = (0..2 * N).map(wave).collect();
    let mut x = x0.clone();
    let mut f = SymBandFactor::default();
    g.bench_function("tridiagonal bordered (SymBand<1> cyclic)", |b| {
        b.iter(|| {
            a.factor_into(&FactorOptions::default(), &mut f).unwrap();
            x.copy_from_slice(&x0);
            f.solve_in_place(&mut x, 2).unwrap();
        })
    });
    let mut fz = SymBandFactor::default();
    let mut xz = x0.clone();
    g.bench_function("tridiagonal zig-zag (SymBand<2> open)", |b| {
        b.iter(|| {
            z.factor_into(&FactorOptions::default(), &mut fz).unwrap();
            for i in 0..N {
                xz[2 * pos[i]..2 * pos[i] + 2].copy_from_slice(&x0[2 * i..2 * i + 2]);
            }
            fz.solve_in_place(&mut xz, 2).unwrap();
            for i in 0..N {
                x[2 * i..2 * i + 2].copy_from_slice(&xz[2 * pos[i]..2 * pos[i] + 2]);
            }
        })
    });
    // Block pentadiagonal, d = 2, one column.
    let d = 2;
    let a = block::<2>(N, d, Topology::Cyclic);
    let mut z = BlockBand::<4>::zeros(N, d, Topology::Open).unwrap();
    let mut blk = vec![0.0; d * d];
    for i in 0..N {
        for k in 0..=2 {
            let j = (i + k) % N;
            a.get(i, j, &mut blk).unwrap();
            if k == 0 {
                z.add(pos[i], pos[i], &blk).unwrap();
            } else {
                z.add(pos[i], pos[j], &blk).unwrap();
            }
        }
    }
    let x0: Vec<f64> = (0..d * N).map(wave).collect();
    let mut x = x0.clone();
    let mut f = BlockFactor::default();
    g.bench_function("block penta d=2 bordered (BlockBand<2> cyclic)", |b| {
        b.iter(|| {
            a.factor_into(&FactorOptions::default(), &mut f).unwrap();
            x.copy_from_slice(&x0);
            f.solve_in_place(&mut x, 1).unwrap();
        })
    });
    let mut fz = BlockFactor::default();
    let mut xz = x0.clone();
    g.bench_function("block penta d=2 zig-zag (BlockBand<4> open)", |b| {
        b.iter(|| {
            z.factor_into(&FactorOptions::default(), &mut fz).unwrap();
            for i in 0..N {
                xz[d * pos[i]..d * pos[i] + d].copy_from_slice(&x0[d * i..d * i + d]);
            }
            fz.solve_in_place(&mut xz, 1).unwrap();
            for i in 0..N {
                x[d * i..d * i + d].copy_from_slice(&xz[d * pos[i]..d * pos[i] + d]);
            }
        })
    });
    g.finish();
}

fn tridiagonal_lu(c: &mut Criterion) {
    let mut g = c.benchmark_group("tridiagonal LU");
    g.sample_size(10).throughput(Throughput::Elements(N as u64));
    let rows: Vec<[f64; 3]> = (0..N)
        .map(|i| [wave(i), 4.0 + wave(i + 1), wave(i + 2)])
        .collect();
    let mut lu = banded::TridiagonalLu::default();
    g.bench_function("factor", |b| {
        b.iter(|| lu.refactor(&rows, banded::PIVOT_RTOL).unwrap())
    });
    let x0: Vec<f64> = (0..N).map(wave).collect();
    let mut x = x0.clone();
    g.bench_function("solve", |b| {
        b.iter(|| {
            x.copy_from_slice(&x0);
            lu.solve_in_place(&mut x, 1).unwrap()
        })
    });
    g.bench_function("solve transposed", |b| {
        b.iter(|| {
            x.copy_from_slice(&x0);
            lu.solve_transposed_in_place(&mut x, 1).unwrap()
        })
    });
    g.finish();
}

fn vectors(c: &mut Criterion) {
    let mut g = c.benchmark_group("vector");
    g.throughput(Throughput::Elements(N as u64));
    let a: Vec<f64> = (0..N).map(wave).collect();
    let b: Vec<f64> = (0..N).map(|k| wave(k + 3)).collect();
    g.bench_function("dot", |bn| bn.iter(|| vector::dot(black_box(&a), &b)));
    g.bench_function("norm (scaled)", |bn| {
        bn.iter(|| vector::norm(black_box(&a)))
    });
    g.bench_function("norm (naive sqrt of sum of squares)", |bn| {
        bn.iter(|| black_box(&a).iter().map(|v| v * v).sum::<f64>().sqrt())
    });
    g.bench_function("dist", |bn| bn.iter(|| vector::dist(black_box(&a), &b)));
    g.finish();
}

criterion_group!(
    kernels,
    scalar_kernels,
    block_kernels,
    cyclic_ordering,
    tridiagonal_lu,
    vectors
);
criterion_main!(kernels);
