//! Newton on Φ on a plateau: a problem of the strip sweep (`xtask/sweeps/strip.py`, seed 3, case
//! 17, sites 50 .. 120 of its 300: clustered sites, noisy values, cubic-piece bounds 6.7e-6 about
//! the data polygon, whose value range is 2.2). From iteration 25 on, the line search accepted
//! steps below one ulp of Φ (≈ 1e16 in the normalized frame) that changed neither Φ nor the f''
//! jumps at the sites, and Newton ran to its 200-iteration limit (442 478 cell solves) before the
//! exchange answered; now the plateau is a stall (`STALL_GRADIENT` in `src/outer/newton.rs`) and
//! the exchange takes over after 25. Its answer is checked independently of the solver
//! (strip-testkit): C² to rounding, the strip exactly, interpolation, and the reported gap.

use std::sync::Mutex;
use strip::{solve_observed, Bound, Options, Problem, Progress};

const T: [f64; 70] = [
    35.334489446138235,
    35.57674296037836,
    35.57696030487925,
    35.577195576998555,
    35.57743233377286,
    35.80116732569479,
    35.801402821706105,
    36.011989648587274,
    36.01219466851034,
    36.222402111632036,
    36.428240225437975,
    36.4284461080041,
    36.63227317198551,
    36.83710501502462,
    36.837311439010705,
    36.83753549154396,
    37.05163492523606,
    37.2936183745128,
    37.29384570460978,
    37.294085453363564,
    37.294316988042155,
    37.532525038105035,
    37.77257662714187,
    37.99023277819903,
    38.201627319608804,
    38.201832509653265,
    38.20207339090145,
    38.202284977064295,
    38.20252654565906,
    38.20275786582934,
    38.20299268438445,
    38.20319605142307,
    38.44196847863295,
    38.44217375034398,
    38.676774229862964,
    38.880113351630044,
    39.12041174202007,
    39.324667258269784,
    39.324875631642264,
    39.32509583542679,
    39.325304797133626,
    39.32551123805209,
    39.542159636405756,
    39.54236389216053,
    39.76767856268438,
    39.99939418904791,
    39.99961626805283,
    40.224416574263415,
    40.22462849726964,
    40.44555438587672,
    40.67274180840852,
    40.91238946930045,
    41.1354134772563,
    41.37703009743456,
    41.595068571601516,
    41.595294945915185,
    41.826730532562756,
    41.82693664621728,
    42.062512413597176,
    42.06274791249876,
    42.06295457256196,
    42.06318308011346,
    42.28182097424604,
    42.491043909679036,
    42.491254567295556,
    42.69878958983155,
    42.938242327597045,
    42.93847751188947,
    42.93870922767621,
    43.14795774815054,
];

const Y: [f64; 70] = [
    1000.3149305387936,
    1000.3526231897367,
    1000.4005829793912,
    1000.4516296619447,
    1000.4845439535627,
    1000.5350874619454,
    1000.548983239178,
    1000.5368677759874,
    1000.5545207347807,
    1000.5861061450674,
    1000.6600344547677,
    1000.6846473047725,
    1000.730777181424,
    1000.8164181909581,
    1000.7656196646669,
    1000.7536472941379,
    1000.788106904478,
    1000.7928120512048,
    1000.7373553321398,
    1000.7977762824146,
    1000.7968525661214,
    1000.7420927775105,
    1000.8548543230249,
    1000.7837072235212,
    1000.78593738498,
    1000.7500999749989,
    1000.7594052269025,
    1000.7949808066128,
    1000.7506036899958,
    1000.7474474487119,
    1000.7427113892027,
    1000.6874584707975,
    1000.7577119639974,
    1000.770423365674,
    1000.7564427512834,
    1000.7205873714296,
    1000.7038994152181,
    1000.7147744180276,
    1000.6906682002062,
    1000.76554982343,
    1000.620900617578,
    1000.4994901634965,
    1000.4872002877847,
    1000.3830145672416,
    1000.3816191346153,
    1000.346070913649,
    1000.3822014591486,
    1000.4086906485876,
    1000.4869308767952,
    1000.5427430978589,
    1000.6178589254628,
    1000.6510835086723,
    1000.7154510650342,
    1000.7470529177459,
    1000.7154859577516,
    1000.6457476613673,
    1000.5783297815543,
    1000.6088707325983,
    1000.4735134757871,
    1000.4862818818833,
    1000.44537101113,
    1000.4904916165235,
    1000.5046424308426,
    1000.463855611893,
    1000.4672622096085,
    1000.3383188672854,
    1000.3565202720491,
    1000.3860933829128,
    1000.2823650394305,
    1000.3346323332329,
];

/// The bounds' half-width about the data polygon.
const W: f64 = 6.707183615617396e-06;

/// The sweep's problem: the data polygon ± W as one linear piece per interval.
fn plateau() -> Problem {
    let band = |side: f64| {
        Bound::Pieces(
            (0..T.len() - 1)
                .map(|i| {
                    [
                        Y[i] + side * W,
                        (Y[i + 1] - Y[i]) / (T[i + 1] - T[i]),
                        0.0,
                        0.0,
                    ]
                })
                .collect(),
        )
    };
    Problem {
        t: T.to_vec(),
        y: Y.to_vec(),
        lower: band(-1.0),
        upper: band(1.0),
        end_slopes: [None, None],
    }
}

#[test]
fn a_plateau_of_newton_hands_over_to_the_exchange() {
    let p = plateau();
    let newton = Mutex::new(0usize);
    let s = solve_observed(&p, &Options::default(), &|e| {
        if let Progress::Newton { iteration, .. } = *e {
            *newton.lock().unwrap() = iteration;
        }
    })
    .expect("the exchange answers");
    let iterations = newton.into_inner().unwrap();
    // 25 here; 200 (the limit) before the plateau was a stall
    assert!(
        (10..=40).contains(&iterations),
        "{iterations} Newton iterations"
    );
    let v = p.y.iter().fold(1.0f64, |m, y| m.max(y.abs()));
    let c2 = strip_testkit::c2_rounding(&p, &s);
    assert!(
        c2.rounding <= 1.0,
        "f'' jumps by {:e} of max|f''| at {} ({}× its rounding level)",
        c2.relative,
        c2.at,
        c2.rounding
    );
    assert!(s.gap <= 1e-9, "gap {:e}", s.gap);
    let viol = strip_testkit::strip_violation(&p, &s);
    assert!(
        viol.by <= 1e-9 * v,
        "strip left by {:e} at {}",
        viol.by,
        viol.at
    );
    let mut q = p.clone();
    for &i in &s.shifted_data {
        q.y[i] = s.grid_values[i];
    }
    let interp = strip_testkit::interpolation_error(&q, &s);
    assert!(interp <= 1e-12 * v, "interpolation {interp:e}");
}
