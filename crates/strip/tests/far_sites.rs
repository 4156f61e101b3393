//! Sites far from the origin: 30 clustered sites (spans 2e-4 and 0.2) near t = 3·10⁶, where one
//! ulp of t is 1e-9 of the range and 2e-6 of the short spans, step values in a band of half-width
//! 1.28 about their polygon (`xtask/sweeps/strip.py`, seed 1, case 87 of its first run, which
//! drew offsets of 10⁶ ranges). Knots closer than an ulp were placed on the same abscissa: 11 of
//! the 124 breaks repeated (pieces of length 0), and 11 touches were reported twice. The answer
//! now has increasing breaks and each contact once, and is checked independently of the solver
//! (strip-testkit): the strip exactly and interpolation.

mod common;

use strip::{solve, Options, Problem};

const T: [f64; 30] = [
    2999999.9999999995,
    3000000.0002042125,
    3000000.201421712,
    3000000.4176311903,
    3000000.6149341483,
    3000000.8348951545,
    3000001.065392814,
    3000001.0656058798,
    3000001.0658196127,
    3000001.2865225,
    3000001.5010159565,
    3000001.714001728,
    3000001.7141993497,
    3000001.714418572,
    3000001.917543676,
    3000001.917763727,
    3000001.917991899,
    3000002.144640763,
    3000002.144873176,
    3000002.145077022,
    3000002.1453071414,
    3000002.145533948,
    3000002.145758121,
    3000002.1459713927,
    3000002.3577700634,
    3000002.5852689343,
    3000002.585477352,
    3000002.5857103304,
    3000002.7993051903,
    3000002.9999999995,
];

const Y: [f64; 30] = [
    100073.45374029923,
    100026.24240551132,
    100075.59520431283,
    100024.1581640177,
    100025.56184774336,
    100074.04093153992,
    100050.85256959476,
    100074.53215345585,
    100025.29569922238,
    100047.6207207321,
    100075.11038965013,
    100076.92861858178,
    100024.18480899144,
    100024.91108108123,
    100027.17260467581,
    99999.86572685732,
    100025.4263922687,
    100051.70102755292,
    100024.73834762383,
    100024.4660631782,
    100075.17663232409,
    100024.35763451122,
    100075.24902139182,
    100073.57276535078,
    100049.92744492179,
    100050.47488387421,
    100074.41516847907,
    99999.89787214213,
    100025.76449395444,
    100001.33857943525,
];

/// The bounds' half-width about the data polygon.
const W: f64 = 1.2765004197281087;

fn far_sites() -> Problem {
    strip_testkit::examples::polygon_band(&T, &Y, W)
}

#[test]
fn knots_within_an_ulp_give_no_empty_piece_and_no_contact_twice() {
    let p = far_sites();
    let s = solve(&p, &Options::default()).expect("an answer");
    assert!(
        s.breaks.windows(2).all(|w| w[0] < w[1]),
        "breaks repeat: {} of {}",
        s.breaks.windows(2).filter(|w| w[0] >= w[1]).count(),
        s.breaks.len()
    );
    assert_eq!(s.coefficients.len() + 1, s.breaks.len());
    assert!(
        s.extra_knots
            .windows(2)
            .all(|k| k[0].t.to_bits() != k[1].t.to_bits() || k[0].kind != k[1].kind),
        "a contact reported twice"
    );
    for t in &p.t {
        assert!(
            s.breaks.binary_search_by(|b| b.total_cmp(t)).is_ok(),
            "site {t} not a break"
        );
    }
    common::assert_keeps_strip_and_data(&p, &s);
}
