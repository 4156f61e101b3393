//! Clusters of very short spans: a net force on the cluster that hides under its vertices'
//! rounding floors (ROBUSTNESS.md item 40). The certificate's arc test (`refine::arcs`) bounds
//! E(p) − E* from below by the net force on runs of vertices; the linear solve refines until its
//! correction is at rounding. The reference objectives were computed in 50- and 60-digit
//! arithmetic (mpmath) on the same knots: H = AᵀA from math.md §1 with the problem's weights,
//! solved by LU.

use divdiff::{Parametrization, Points, Topology};
use refine::{Constraint, Problem, Refinement};

/// E + ½ Σ w_i |p_{i_k} − q_i|²: smoothing's objective.
fn objective(r: &Refinement, q: &Points, w: &[f64]) -> f64 {
    let penalty: f64 = r
        .data_vertex
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let (p, q) = (r.points.point(v), q.point(i));
            0.5 * w[i] * p.iter().zip(q).map(|(a, b)| (a - b).powi(2)).sum::<f64>()
        })
        .sum();
    r.energy + penalty
}

/// Smoothing (weights 1) of eight points on an arc whose every other chord is 1e4 times shorter,
/// chordal knots, no knot update: one step of iterative refinement left the answer 0.57 % above
/// the optimal objective (0.063745 against 0.0633807) and the per-vertex certificate passed it at
/// 1e-11. It is now solved to 1e-9 of the optimum.
#[test]
fn smoothing_on_spans_1e4_apart_is_the_optimum() {
    let mut pts = Vec::new();
    let mut th = 0.0f64;
    for i in 0..8 {
        pts.push([2.0 * th.cos(), th.sin()]);
        th += if i % 2 == 0 { 0.4 } else { 0.4 / 1e4 };
    }
    let q = Points::from_rows(&pts).unwrap();
    let w = vec![1.0; 8];
    let r = Problem::new(q.clone())
        .with_topology(Topology::Open)
        .with_parametrization(Parametrization::Chordal)
        .with_knot_iterations(0)
        .with_constraint(Constraint::Smoothing(w.clone()))
        .solve()
        .expect("certified");
    // mpmath, 50 digits, on the chordal knots of these points with k = 3.
    let optimum = 0.063_380_698_592_102_8;
    let got = objective(&r, &q, &w);
    assert!(
        (got - optimum).abs() <= 1e-9 * optimum,
        "objective {got} against the optimum {optimum}"
    );
}

/// Found by `xtask/sweeps/optimality.py` (refine seed 67, case 186): smoothing of three points
/// on a closed curve, k = 3, exponent 1.82, three knot updates, which leave spans of 1.8e-6
/// beside spans of 13. The answer was certified at 7e-12 with the four vertices around the first
/// data vertex 1.15 from where they belong: objective 7.5497 against 6.6031 on the same knots.
/// The arc test refuses one step of refinement there (its bound alone, 0.94 of the 0.95
/// excess), and the stage is solved again with refinement to rounding: the optimum.
#[test]
fn a_cluster_pushed_off_its_data_is_brought_back() {
    let q = Points::from_rows(&[
        [1.624_462_213_403_149_4, 8.040_797_346_163_407e-7],
        [5.630_324_699_662_252_5, -8.400_956_229_193_435e-7],
        [6.558_583_218_589_603, -2.202_381_821_078_287e-7],
    ])
    .unwrap();
    let w = vec![
        1.430_054_181_048_899_4,
        15.116_081_049_705_047,
        96_286.370_231_600_61,
    ];
    let r = Problem::new(q.clone())
        .with_topology(Topology::Closed)
        .with_k(3)
        .with_knot_iterations(3)
        .with_parametrization(Parametrization::Exponent(1.817_793_960_299_685))
        .with_constraint(Constraint::Smoothing(w.clone()))
        .solve()
        .expect("certified");
    // The reference is the optimum on these knots (the last stage's, set by the stages before
    // it): mpmath, 60 digits, 6.6030872620193381555.
    let t = r.knots.values();
    let last = t[t.len() - 1];
    assert!(
        (last - 31.536_855_537_489_913).abs() <= 1e-12 * last,
        "other knots (last {last}): recompute the reference"
    );
    let optimum = 6.603_087_262_019_338;
    let got = objective(&r, &q, &w);
    assert!(
        (got - optimum).abs() <= 1e-9 * optimum,
        "objective {got} against the optimum {optimum}"
    );
}
