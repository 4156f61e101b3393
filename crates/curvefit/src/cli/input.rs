//! Reading problems: JSON and CSV, streamed from the file (or standard input) into the typed
//! problem, with memory bounded by the input.
//!
//! No more than 8 MiB of the input text is held ([`READ_WHOLE_BYTES`]: smaller inputs are parsed
//! from memory, faster; larger ones stream from a buffered reader) and the parser reads straight
//! into the typed problem, whose `points` go into one flat vector ([`crate::spec::Rows`]); a CSV
//! is read line by line into a flat vector. Peak memory is therefore the parsed data (8 bytes per
//! coordinate, ≤ 4 × the input even for one-digit numbers) plus at most 8 MiB; arrays are
//! refused as soon as they pass their limit ([`crate::spec::MAX_POINT_COORDS`]), and a regular
//! file above [`MAX_INPUT_BYTES`] is refused from its size before a byte is read.

use std::io::{BufRead, Read};
use std::path::Path;

use super::InputError;

/// Largest problem file accepted (bytes); a larger regular file is refused from its size, a
/// larger stream when it passes the limit.
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// Read buffer size.
const BUFFER: usize = 1 << 16;

/// A reader that fails once more than [`MAX_INPUT_BYTES`] have been read, remembering why in
/// `exceeded`. It sits *under* the `BufReader`: the parser reads byte by byte, and std's
/// `BufReader` serves those from its buffer (a wrapper above it would make every byte a call).
struct Limited<'a, R> {
    inner: R,
    read: u64,
    exceeded: &'a std::cell::Cell<bool>,
}

impl<R: Read> Read for Limited<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read += n as u64;
        if self.read > MAX_INPUT_BYTES {
            self.exceeded.set(true);
            return Err(std::io::Error::other("input too large"));
        }
        Ok(n)
    }
}

fn too_large(what: &str) -> InputError {
    InputError::new(
        "problem",
        format!("{what} is larger than {MAX_INPUT_BYTES} bytes, the input limit"),
    )
}

/// Opens a problem or CSV file; a regular file above [`MAX_INPUT_BYTES`] is refused from its
/// size. `field` names the argument in errors.
pub fn open(path: &Path, field: &str) -> Result<std::fs::File, InputError> {
    let file = std::fs::File::open(path)
        .map_err(|e| InputError::new(field, format!("cannot open {}: {e}", path.display())))?;
    match file.metadata() {
        Ok(m) if m.is_file() && m.len() > MAX_INPUT_BYTES => {
            Err(too_large(&path.display().to_string()))
        }
        Ok(m) if m.is_dir() => Err(InputError::new(
            field,
            format!("{} is a directory, not a file", path.display()),
        )),
        _ => Ok(file),
    }
}

/// Inputs up to this size are read whole and parsed from memory (serde_json's slice reader
/// runs ~30 % fewer instructions than its byte-wise stream reader: 157 against 219 million on a
/// 4.3 MB problem); larger ones are streamed, holding only this prefix.
pub const READ_WHOLE_BYTES: usize = 8 << 20;

/// Parses a JSON problem from `reader` (`what` names it in messages): read whole when it is at
/// most [`READ_WHOLE_BYTES`], else streamed (the first [`READ_WHOLE_BYTES`] held, then the rest
/// through a buffer), so memory is the parsed problem plus at most 8 MiB.
///
/// # Errors
/// Malformed JSON (`problem`), a field that is wrong (its path), an input above the limit.
pub fn read_json<P: serde::de::DeserializeOwned>(
    reader: impl Read,
    what: &str,
) -> Result<P, InputError> {
    read_json_with(reader, what, |_| None)
}

/// [`read_json`] of a problem whose large arrays (`points`, …) the fast path reads
/// ([`super::fastjson`]: the same numbers, and every error still serde_json's) when the input is
/// read whole.
///
/// # Errors
/// As [`read_json`].
pub fn read_problem<P: crate::spec::arrays::LargeArrays>(
    reader: impl Read,
    what: &str,
) -> Result<P, InputError> {
    read_json_with(reader, what, super::fastjson::read::<P>)
}

/// [`read_problem`] of the file `path` (`field` names the argument in errors). A regular file of
/// [`super::fastjson::PARALLEL_BYTES`] to [`READ_WHOLE_BYTES`] is read whole, its two halves on
/// two threads: reading into fresh memory costs a page fault per 4 KiB (~4 µs each on the 2-core
/// development machine, 4 ms for a 4 MB problem), and the halves' faults happen on both cores.
///
/// # Errors
/// As [`read_json`], and a file that cannot be opened.
pub fn read_problem_file<P: crate::spec::arrays::LargeArrays>(
    path: &Path,
    field: &str,
) -> Result<P, InputError> {
    let file = open(path, field)?;
    match read_halves(&file) {
        Some(bytes) => parse_whole(&bytes, super::fastjson::read::<P>),
        // Anything unusual (a stream, a file that changed while it was read, a read error):
        // read from the start as a stream, which words its errors.
        None => read_problem(file, &path.display().to_string()),
    }
}

/// The whole of a regular file of [`super::fastjson::PARALLEL_BYTES`] to [`READ_WHOLE_BYTES`],
/// read in two halves on two threads (positioned reads: the file's cursor stays at its start),
/// or `None`.
#[cfg(unix)]
fn read_halves(file: &std::fs::File) -> Option<Vec<u8>> {
    use std::os::unix::fs::FileExt;
    let meta = file.metadata().ok()?;
    let len = usize::try_from(meta.len()).ok()?;
    if !meta.is_file() || !(super::fastjson::PARALLEL_BYTES..=READ_WHOLE_BYTES).contains(&len) {
        return None;
    }
    // Zeroed by the allocator (fresh pages), so the reads are the first to touch them.
    let mut bytes = vec![0u8; len];
    let (first, second) = bytes.split_at_mut(len / 2);
    let read = std::thread::scope(|s| {
        let other = s.spawn(|| file.read_exact_at(second, (len / 2) as u64));
        let mine = file.read_exact_at(first, 0);
        mine.is_ok() && other.join().is_ok_and(|r| r.is_ok())
    });
    // A file that grew while it was read is read as a stream.
    let grew = file.read_at(&mut [0u8], len as u64).ok()? > 0;
    (read && !grew).then_some(bytes)
}

#[cfg(not(unix))]
fn read_halves(_: &std::fs::File) -> Option<Vec<u8>> {
    None
}

/// A problem held whole in memory: `fast` first, else serde_json.
fn parse_whole<P: serde::de::DeserializeOwned>(
    bytes: &[u8],
    fast: impl FnOnce(&[u8]) -> Option<P>,
) -> Result<P, InputError> {
    // A problem is an object (serde would read an array as the struct's fields in order).
    crate::spec::not_an_object(bytes.iter().copied().find(|b| !b.is_ascii_whitespace()))?;
    match fast(bytes) {
        Some(p) => Ok(p),
        None => crate::spec::from_json_bytes(bytes),
    }
}

/// [`read_json`], trying `fast` first on an input read whole.
fn read_json_with<P: serde::de::DeserializeOwned>(
    reader: impl Read,
    what: &str,
    fast: impl FnOnce(&[u8]) -> Option<P>,
) -> Result<P, InputError> {
    let exceeded = std::cell::Cell::new(false);
    let mut limited = Limited {
        inner: reader,
        read: 0,
        exceeded: &exceeded,
    };
    let read_error = |e: std::io::Error| {
        if exceeded.get() {
            too_large(what)
        } else {
            InputError::new("problem", format!("cannot read {what}: {e}"))
        }
    };
    let mut prefix = Vec::new();
    (&mut limited)
        .take(READ_WHOLE_BYTES as u64 + 1)
        .read_to_end(&mut prefix)
        .map_err(read_error)?;
    let end = |e: serde_json::Error| InputError::new("problem", format!("malformed JSON: {e}"));
    let result = if prefix.len() <= READ_WHOLE_BYTES {
        parse_whole(&prefix, fast)
    } else {
        // A problem is an object (serde would read an array as the struct's fields in order).
        crate::spec::not_an_object(prefix.iter().copied().find(|b| !b.is_ascii_whitespace()))?;
        let rest = std::io::Cursor::new(&prefix[..]).chain(limited);
        let mut de =
            serde_json::Deserializer::from_reader(std::io::BufReader::with_capacity(BUFFER, rest));
        crate::spec::from_deserializer(&mut de).and_then(|p| {
            de.end().map_err(end)?;
            Ok(p)
        })
    };
    match result {
        Err(_) if exceeded.get() => Err(too_large(what)),
        Err(e) if e.message.starts_with("malformed JSON: io error") => Err(InputError::new(
            "problem",
            format!("cannot read {what}: {}", e.message),
        )),
        r => r,
    }
}

/// Points read from a CSV file: one point per line, its coordinates separated by commas
/// (whitespace around a number is ignored); an optional header line (a first line none of whose
/// fields is a name starting with a letter, e.g. `x,y`); blank lines and lines starting with `#` are skipped. Every
/// other deviation — a semicolon or whitespace as separator, a trailing comma, an empty field,
/// rows of different lengths — is an error naming the line.
pub struct Csv {
    /// The points, flat.
    pub points: divdiff::Points,
    /// The header's column names, if the file has one.
    pub header: Option<Vec<String>>,
}

/// Reads a CSV of points (see [`Csv`]), streaming line by line, refusing more than
/// [`crate::spec::MAX_POINT_COORDS`] coordinates as soon as it passes them.
///
/// # Errors
/// An [`InputError`] naming `points[i]` (the data row) and the line.
pub fn read_csv(reader: impl Read, what: &str) -> Result<Csv, InputError> {
    read_csv_limited(reader, what, crate::spec::MAX_POINT_COORDS)
}

/// [`read_csv`] with at most `max_coords` coordinates.
///
/// # Errors
/// As [`read_csv`].
pub fn read_csv_limited(
    reader: impl Read,
    what: &str,
    max_coords: usize,
) -> Result<Csv, InputError> {
    let exceeded = std::cell::Cell::new(false);
    let limited = Limited {
        inner: reader,
        read: 0,
        exceeded: &exceeded,
    };
    let mut r = std::io::BufReader::with_capacity(BUFFER, limited);
    let mut line = Vec::new();
    let mut coords: Vec<f64> = Vec::new();
    let mut dim = 0usize;
    let mut rows = 0usize;
    let mut header = None;
    let mut lineno = 0usize;
    loop {
        line.clear();
        let n = match r.read_until(b'\n', &mut line) {
            Ok(n) => n,
            Err(_) if exceeded.get() => return Err(too_large(what)),
            Err(e) => {
                return Err(InputError::new(
                    "--points",
                    format!("cannot read {what}: {e}"),
                ))
            }
        };
        if n == 0 {
            break;
        }
        lineno += 1;
        let text = std::str::from_utf8(&line).map_err(|_| {
            InputError::new(
                format!("points[{rows}]"),
                format!("line {lineno} of {what} is not UTF-8 text"),
            )
        })?;
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let row_error = |msg: String| {
            InputError::new(
                format!("points[{rows}]"),
                format!("line {lineno} of {what}: {msg}"),
            )
        };
        let start = coords.len();
        let mut numbers = 0usize;
        let mut names = Vec::new();
        for field in text.split(',') {
            let f = field.trim();
            if f.is_empty() {
                return Err(row_error(if text.ends_with(',') {
                    "a trailing comma (the separator is a comma between numbers)".into()
                } else {
                    "an empty field".into()
                }));
            }
            match f.parse::<f64>() {
                Ok(x) if x.is_finite() => {
                    if coords.len() >= max_coords {
                        return Err(InputError::new(
                            "points",
                            crate::spec::points::too_large("coordinates", max_coords),
                        ));
                    }
                    coords.push(x);
                    numbers += 1;
                }
                Ok(_) => return Err(row_error(format!("`{f}` is not a finite number"))),
                Err(_) => names.push(f.to_string()),
            }
        }
        if !names.is_empty() {
            coords.truncate(start);
            // A header: the first line, every field a name (starting with a letter, `_` or a
            // quote), so that `0;1` is a wrong separator and not a header.
            let is_name = |s: &String| {
                s.starts_with(|c: char| c.is_alphabetic() || c == '_' || c == '"')
                    && !s.contains([';', '\t'])
            };
            if rows == 0 && header.is_none() && numbers == 0 && names.iter().all(is_name) {
                header = Some(names);
                continue;
            }
            let bad = &names[0];
            let hint = if bad.contains(';') {
                " (the separator is a comma, not a semicolon)"
            } else if bad.split_whitespace().count() > 1 {
                " (the separator is a comma, not whitespace)"
            } else {
                ""
            };
            return Err(row_error(format!("`{bad}` is not a number{hint}")));
        }
        if rows == 0 {
            dim = numbers;
            if let Some(h) = &header {
                if h.len() != dim {
                    return Err(row_error(format!(
                        "{dim} numbers, but the header has {} columns",
                        h.len()
                    )));
                }
            }
        } else if numbers != dim {
            return Err(row_error(format!(
                "{numbers} numbers, expected {dim} like the first row"
            )));
        }
        rows += 1;
    }
    coords.shrink_to_fit();
    let points = if rows == 0 {
        divdiff::Points::default()
    } else {
        divdiff::Points::new(dim, coords).map_err(|e| InputError::new("points", e))?
    };
    Ok(Csv { points, header })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csv(s: &str) -> Result<Csv, InputError> {
        read_csv(s.as_bytes(), "f.csv")
    }

    #[test]
    fn csv_with_and_without_header() {
        let c = csv("x, y\n0, 1\n2,3.5\r\n\n# note\n4 ,5\n").unwrap();
        assert_eq!(
            c.header.as_deref(),
            Some(&["x".to_string(), "y".to_string()][..])
        );
        assert_eq!(c.points.coords(), &[0.0, 1.0, 2.0, 3.5, 4.0, 5.0]);
        let c = csv("1\n2\n3").unwrap();
        assert!(c.header.is_none());
        assert_eq!((c.points.len(), c.points.dim()), (3, 1));
        assert!(csv("").unwrap().points.is_empty());
    }

    #[test]
    fn csv_errors_name_the_line() {
        for (text, field, words) in [
            ("0;1\n", "points[0]", "line 1 of f.csv: `0;1` is not a number (the separator is a comma, not a semicolon)"),
            ("0,1\n2,3,\n", "points[1]", "line 2 of f.csv: a trailing comma"),
            ("0,1\n2 3\n", "points[1]", "not whitespace"),
            ("0,1\n2,,3\n", "points[1]", "an empty field"),
            ("0,1\n2,3,4\n", "points[1]", "3 numbers, expected 2"),
            ("x,y\n1\n", "points[0]", "the header has 2 columns"),
            ("0,1\nx,y\n", "points[1]", "`x` is not a number"),
            ("0,inf\n", "points[0]", "not a finite number"),
        ] {
            let e = csv(text).err().unwrap_or_else(|| panic!("{text:?} accepted"));
            assert_eq!(e.field, field, "{text:?}: {e}");
            assert!(e.message.contains(words), "{text:?}: {e}");
        }
    }

    /// A large file read in halves gives the problem and the errors of the stream reader.
    #[test]
    fn files_read_in_halves_read_as_streams() {
        use crate::spec::RefineProblem;
        let dir = std::env::temp_dir().join(format!("curvefit-halves-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rows: Vec<String> = (0..60_000)
            .map(|i| format!("[{}, {}]", i as f64 * 0.25, (i as f64).sin()))
            .collect();
        let good = format!("{{\"points\": [{}], \"k\": 2}}", rows.join(", "));
        assert!(good.len() > super::super::fastjson::PARALLEL_BYTES);
        let bad_row = good.replacen("[7.5, ", "[7.5, 1, ", 1);
        let docs = [
            good.clone(),
            bad_row,
            good.replacen("\"k\": 2", "\"k\": -2", 1),
            good.replacen('}', "", 1),
            format!("[{good}]"),
        ];
        for (i, doc) in docs.iter().enumerate() {
            let path = dir.join(format!("p{i}.json"));
            std::fs::write(&path, doc).unwrap();
            let halves = read_problem_file::<RefineProblem>(&path, "problem");
            let stream = read_problem::<RefineProblem>(std::fs::File::open(&path).unwrap(), "x");
            match (halves, stream) {
                (Ok(a), Ok(b)) => assert_eq!(
                    serde_json::to_string(&a).unwrap(),
                    serde_json::to_string(&b).unwrap()
                ),
                (Err(a), Err(b)) => assert_eq!(a, b, "doc {i}"),
                (a, b) => panic!("doc {i}: {:?} against {:?}", a.err(), b.err()),
            }
        }
        assert!(
            read_problem_file::<RefineProblem>(&dir.join("p1.json"), "problem")
                .unwrap_err()
                .field
                .starts_with("points[30")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn json_streams_into_the_problem() {
        let p: crate::spec::RefineProblem =
            read_json(&br#"{"points": [[0, 0], [1, 0], [0, 1]]}"#[..], "f.json").unwrap();
        assert_eq!(p.points.len(), 3);
        let e = read_json::<crate::spec::RefineProblem>(&b"{\"points\": [[0, 0], [1"[..], "f")
            .unwrap_err();
        assert_eq!(e.field, "problem");
        assert!(e.message.starts_with("malformed JSON"), "{e}");
    }
}
