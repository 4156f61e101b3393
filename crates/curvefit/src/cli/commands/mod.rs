//! One file per subcommand: its [`Command`](super::Command) (the solve is the library's
//! [`crate::spec`] entry point) and its picture.

pub mod natural;
pub mod refine;
pub mod strip;
pub mod surface;

use crate::spec::{InputError, Rows};

/// `--points FILE.csv` into a problem's `points`, which must not be given twice.
fn set_points(points: &mut Rows, csv: super::input::Csv) -> Result<(), InputError> {
    if !points.is_empty() {
        return Err(InputError::new(
            "points",
            "given both in the problem and by --points",
        ));
    }
    *points = Rows(csv.points);
    Ok(())
}

/// The fast path's checks against serde_json ([`super::fastjson`]).
#[cfg(test)]
mod fast_path_tests {
    use super::super::fastjson::read;
    use crate::spec::arrays::LargeArrays;
    use crate::spec::{self, from_json_bytes};

    /// The problem as serde_json reads it, written back (floats as their shortest round
    /// trip, so equal texts are equal bits).
    fn serde<P: LargeArrays + serde::Serialize>(doc: &[u8]) -> Result<String, spec::InputError> {
        from_json_bytes::<P>(doc).map(|p| serde_json::to_string(&p).unwrap())
    }

    /// `doc` read by the fast path: `None`, or what serde_json reads.
    fn check<P: LargeArrays + serde::Serialize>(doc: &[u8]) -> bool {
        let Some(fast) = read::<P>(doc) else {
            return false;
        };
        let slow = serde::<P>(doc).unwrap_or_else(|e| {
            panic!(
                "{}: fast path read it, serde_json says {e}",
                String::from_utf8_lossy(doc)
            )
        });
        assert_eq!(
            serde_json::to_string(&fast).unwrap(),
            slow,
            "{}",
            String::from_utf8_lossy(doc)
        );
        true
    }

    #[test]
    fn every_example_reads_as_serde_json_reads_it() {
        let dirs = [
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/problems"),
            concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data"),
        ];
        let mut fast = 0;
        for dir in dirs {
            for e in std::fs::read_dir(dir).unwrap() {
                let path = e.unwrap().path();
                let name = path.file_name().unwrap().to_string_lossy().into_owned();
                let doc = std::fs::read(&path).unwrap();
                let took = match name.split('-').next().unwrap() {
                    "refine" => check::<spec::RefineProblem>(&doc),
                    "strip" => check::<spec::StripProblem>(&doc),
                    "natural" => check::<spec::NaturalProblem>(&doc),
                    "surface" => check::<spec::SurfaceProblem>(&doc),
                    "polygon" => check::<spec::scheme::PolygonInput>(&doc),
                    _ => continue,
                };
                assert!(took, "{name}: left to serde_json");
                fast += 1;
            }
        }
        assert!(fast >= 20, "{fast}");
    }

    /// Random edits of problems with every large array: whatever the fast path reads,
    /// serde_json reads the same; whatever serde_json refuses, the fast path leaves to it
    /// (so the error is serde_json's, field and index).
    #[test]
    fn edited_documents_read_as_serde_json_reads_them() {
        let docs: [(&str, &[u8]); 3] = [
            ("refine", br#"{"points": [[0, 0.5], [1e0, -2], [3.25, 4E-1], [-0, 7]], "closed": true,
                "knots": [0, 1, 2, 3.5, 4], "constraint": {"type": "balls", "radii": [0.1, 0, 2e-3, 1]}, "k": 2}"#),
            ("refine", br#"{"constraint": {"weights": [1, 2.5, 3], "type": "smoothing"}, "points": [[1], [2], [3.5]]}"#),
            ("strip", br#"{"t": [0, 1, 2.5, 3], "y": [1, -1e-3, 2, 0.5], "lower": null}"#),
        ];
        let edits: &[u8] = b"0-.eE,[]\"{} x1+:n";
        let mut s: u64 = 0x2545_F491_4F6C_DD1D;
        let mut next = move |m: usize| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % m as u64) as usize
        };
        let (mut taken, mut total) = (0, 0);
        for (kind, doc) in docs {
            for _ in 0..4000 {
                let mut d = doc.to_vec();
                for _ in 0..1 + next(2) {
                    let at = next(d.len());
                    match next(3) {
                        0 => d[at] = edits[next(edits.len())],
                        1 => {
                            d.remove(at);
                        }
                        _ => d.insert(at, edits[next(edits.len())]),
                    }
                }
                if d.first() != Some(&b'{') {
                    continue;
                }
                total += 1;
                let took = match kind {
                    "refine" => check::<spec::RefineProblem>(&d),
                    _ => check::<spec::StripProblem>(&d),
                };
                taken += usize::from(took);
            }
        }
        // Most edits break the document (serde_json refuses it: the fast path must leave
        // it); some keep it valid, and the fast path reads those (800 of 11818 here).
        assert!(taken > total / 20, "{taken} of {total}");
    }
}
