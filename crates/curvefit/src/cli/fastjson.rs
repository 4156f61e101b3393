//! The fast path of reading a JSON problem held in memory: its large numeric arrays (`points`,
//! `constraint.radii`, `t`, …) are parsed here, split over the cores, and the rest of the
//! document by serde_json as before.
//!
//! serde_json reads a number at ~85 ns (it collects the digits and converts them with its own
//! correctly rounded algorithm); here each number is converted in place by `lexical-core` with
//! the JSON number grammar (`lexical_core::format::JSON`: no leading zeros, no `1.` or `.5`, no
//! `+1`, no `inf`), correctly rounded like serde_json's `float_roundtrip` parser, so the doubles
//! are the same bits. Arrays of rows `[[x, y], …]` longer than [`PARALLEL_BYTES`] are cut at row
//! boundaries into one piece per core.
//!
//! The fast path only ever *accepts*: whatever it does not recognize — an array with anything
//! but numbers in the expected shape, rows of different lengths, a number out of range, a key
//! given twice, more entries than the field's limit — it leaves to serde_json. The document is
//! then parsed by serde_json with each recognized array replaced by `[]`, and the arrays are put
//! into the problem; if that parse fails, or the problem has no place for an array, [`read`]
//! returns `None` and the caller parses the whole document as before, so every error message
//! (field, index, wording) is serde_json's, unchanged.

use crate::spec::arrays::{Array, Kind, LargeArrays, Parsed};

/// Array texts at least this long (bytes from the array's start to the end of the document)
/// are parsed on every core.
pub const PARALLEL_BYTES: usize = 1 << 20;

/// Most threads used for one array.
const MAX_THREADS: usize = 8;

/// The problem in `bytes` (a JSON object), its large arrays parsed by the fast path; `None`
/// when the document has none of them, or anything about it is unusual (see the module docs):
/// then parse it with serde_json.
pub fn read<P: LargeArrays>(bytes: &[u8]) -> Option<P> {
    if P::ARRAYS.is_empty() {
        return None;
    }
    let mut found: Vec<(usize, usize, usize, Parsed)> = Vec::new();
    let mut s = Scan { b: bytes, i: 0 };
    s.object(P::ARRAYS, 0, &mut found)?;
    if found.is_empty() {
        return None;
    }
    found.sort_by_key(|f| f.1);
    let mut rest = Vec::with_capacity(
        bytes.len() - found.iter().map(|f| f.2 - f.1).sum::<usize>() + 2 * found.len(),
    );
    let mut at = 0;
    for f in &found {
        rest.extend_from_slice(&bytes[at..f.1]);
        rest.extend_from_slice(b"[]");
        at = f.2;
    }
    rest.extend_from_slice(&bytes[at..]);
    serde_json::from_slice::<P>(&rest)
        .ok()?
        .with_arrays(found.into_iter().map(|(i, _, _, value)| (i, value)))
}

/// A cursor over the document.
struct Scan<'a> {
    b: &'a [u8],
    i: usize,
}

/// JSON whitespace.
#[inline(always)]
fn is_ws(c: u8) -> bool {
    matches!(c, b' ' | b'\n' | b'\r' | b'\t')
}

#[inline(always)]
fn skip_ws(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && is_ws(b[i]) {
        i += 1;
    }
    i
}

impl<'a> Scan<'a> {
    fn peek(&mut self) -> Option<u8> {
        self.i = skip_ws(self.b, self.i);
        self.b.get(self.i).copied()
    }

    fn eat(&mut self, c: u8) -> Option<()> {
        (self.peek()? == c).then(|| self.i += 1)
    }

    /// A string at the cursor: its raw bytes between the quotes (escapes not decoded).
    fn string(&mut self) -> Option<&'a [u8]> {
        self.eat(b'"')?;
        let start = self.i;
        loop {
            match *self.b.get(self.i)? {
                b'"' => break,
                b'\\' => self.i += 2,
                _ => self.i += 1,
            }
        }
        self.i += 1;
        Some(&self.b[start..self.i - 1])
    }

    /// Skips one value, checking only its nesting (serde_json checks the rest).
    fn skip_value(&mut self) -> Option<()> {
        match self.peek()? {
            b'"' => self.string().map(drop),
            b'{' | b'[' => {
                let mut depth = 0usize;
                loop {
                    match *self.b.get(self.i)? {
                        b'"' => {
                            self.string()?;
                            continue;
                        }
                        b'{' | b'[' => depth += 1,
                        b'}' | b']' => {
                            depth -= 1;
                            if depth == 0 {
                                self.i += 1;
                                return Some(());
                            }
                        }
                        _ => {}
                    }
                    self.i += 1;
                }
            }
            _ => {
                while self
                    .b
                    .get(self.i)
                    .is_some_and(|&c| !matches!(c, b',' | b'}' | b']') && !is_ws(c))
                {
                    self.i += 1;
                }
                Some(())
            }
        }
    }

    /// An object at the cursor, at `depth` keys below the top: the arrays of `arrays` in it are
    /// parsed into `found` (index, start, end, value).
    fn object(
        &mut self,
        arrays: &[Array],
        depth: usize,
        found: &mut Vec<(usize, usize, usize, Parsed)>,
    ) -> Option<()> {
        self.eat(b'{')?;
        if self.peek()? == b'}' {
            self.i += 1;
            return Some(());
        }
        loop {
            let key = self.string()?;
            self.eat(b':')?;
            self.peek()?;
            let here = |a: &Array| a.path.get(depth).is_some_and(|k| k.as_bytes() == key);
            let leaf = arrays
                .iter()
                .position(|a| here(a) && a.path.len() == depth + 1);
            let inner = arrays.iter().any(|a| here(a) && a.path.len() > depth + 1);
            match (leaf, self.b[self.i]) {
                (Some(k), b'[') => {
                    if found.iter().any(|f| f.0 == k) {
                        return None; // a key given twice: serde_json's error
                    }
                    let start = self.i;
                    match parse_array(self.b, start, arrays[k].kind) {
                        Some((value, end)) => {
                            found.push((k, start, end, value));
                            self.i = end;
                        }
                        None => self.skip_value()?,
                    }
                }
                _ if inner && self.b[self.i] == b'{' => self.object(arrays, depth + 1, found)?,
                _ => self.skip_value()?,
            }
            match self.peek()? {
                b',' => self.i += 1,
                b'}' => {
                    self.i += 1;
                    return Some(());
                }
                _ => return None,
            }
        }
    }
}

/// The array at `start` (its `[`), parsed as `kind`, and the position after it; `None` for
/// anything else.
fn parse_array(b: &[u8], start: usize, kind: Kind) -> Option<(Parsed, usize)> {
    match kind {
        Kind::Numbers { max } => {
            let mut out = Vec::new();
            let end = numbers(b, start + 1, b']', max, &mut out)?;
            if out.is_empty() {
                return None;
            }
            out.shrink_to_fit();
            Some((Parsed::Numbers(out), end))
        }
        Kind::Rows { max } => {
            let (coords, dim, end) = rows_parallel(b, start, max)?;
            let points = divdiff::Points::new(dim, coords).ok()?;
            Some((Parsed::Rows(points), end))
        }
    }
}

const JSON: u128 = lexical_core::format::JSON;

/// Numbers separated by commas from `i` up to the closing `close`, appended to `out` (at most
/// `max` in all); the position after `close`.
#[inline]
fn numbers(b: &[u8], mut i: usize, close: u8, max: usize, out: &mut Vec<f64>) -> Option<usize> {
    let options = lexical_core::ParseFloatOptions::new();
    loop {
        i = skip_ws(b, i);
        let (x, n) =
            lexical_core::parse_partial_with_options::<f64, JSON>(b.get(i..)?, &options).ok()?;
        // serde_json refuses a number beyond f64's range ("number out of range").
        if n == 0 || !x.is_finite() || out.len() >= max {
            return None;
        }
        out.push(x);
        i = skip_ws(b, i + n);
        match *b.get(i)? {
            b',' => i += 1,
            c if c == close => return Some(i + 1),
            _ => return None,
        }
    }
}

/// One piece of a rows array: rows `[…]` separated by commas from `i` (a row's `[`), up to the
/// separator at `stop` or the array's closing `]`.
struct Piece {
    coords: Vec<f64>,
    dim: usize,
    /// The position after the closing `]` when the piece ended the array, else `None` (it
    /// stopped at `stop`).
    end: Option<usize>,
}

fn piece(b: &[u8], mut i: usize, stop: usize, max: usize, capacity: usize) -> Option<Piece> {
    let mut coords = Vec::with_capacity(capacity);
    let mut dim = 0;
    loop {
        i = skip_ws(b, i);
        if *b.get(i)? != b'[' {
            return None;
        }
        let before = coords.len();
        i = numbers(b, i + 1, b']', max, &mut coords)?;
        let d = coords.len() - before;
        if dim == 0 {
            dim = d;
        } else if d != dim {
            return None;
        }
        i = skip_ws(b, i);
        match *b.get(i)? {
            b',' if i == stop => {
                return Some(Piece {
                    coords,
                    dim,
                    end: None,
                })
            }
            b',' => i += 1,
            b']' => {
                return Some(Piece {
                    coords,
                    dim,
                    end: Some(i + 1),
                })
            }
            _ => return None,
        }
    }
}

/// A row separator (`,` after a row's `]`) at or after `from`, where a rows array could be cut.
fn separator_after(b: &[u8], from: usize) -> Option<usize> {
    let close = from + b.get(from..)?.iter().position(|&c| c == b']')?;
    let j = skip_ws(b, close + 1);
    (b.get(j) == Some(&b',')).then_some(j)
}

/// The rows array at `start`: its coordinates, dimension and the position after it. Long texts
/// are cut at row separators into one piece per core; a piece is used only when the one before
/// it stopped exactly at its separator (so the cut is inside this array, whatever follows it).
fn rows_parallel(b: &[u8], start: usize, max: usize) -> Option<(Vec<f64>, usize, usize)> {
    let first = skip_ws(b, start + 1);
    let len = b.len() - start;
    let threads = if len >= PARALLEL_BYTES {
        std::thread::available_parallelism().map_or(1, |n| n.get().min(MAX_THREADS))
    } else {
        1
    };
    // The separators cutting the text into `threads` pieces (fewer when none is found).
    let mut stops: Vec<usize> = Vec::new();
    for t in 1..threads {
        let from = (start + len * t / threads).max(stops.last().map_or(first, |&s| s + 1));
        match separator_after(b, from) {
            Some(s) => stops.push(s),
            None => break,
        }
    }
    // A rough size per piece: a coordinate takes at least two bytes (`0,`).
    let capacity = |from: usize, to: usize| (to - from) / 12;
    let pieces: Vec<Option<Piece>> = if stops.is_empty() {
        vec![piece(b, first, usize::MAX, max, capacity(first, b.len()))]
    } else {
        std::thread::scope(|s| {
            let handles: Vec<_> = stops
                .iter()
                .enumerate()
                .map(|(t, &from)| {
                    let to = stops.get(t + 1).copied().unwrap_or(usize::MAX);
                    s.spawn(move || piece(b, from + 1, to, max, capacity(from, to.min(b.len()))))
                })
                .collect();
            let mut all = vec![piece(b, first, stops[0], max, capacity(first, stops[0]))];
            all.extend(handles.into_iter().map(|h| h.join().ok().flatten()));
            all
        })
    };
    let mut coords: Vec<f64> = Vec::new();
    let mut dim = 0;
    for p in pieces {
        let p = p?;
        if dim != 0 && p.dim != dim {
            return None;
        }
        dim = p.dim;
        if coords.is_empty() {
            coords = p.coords;
        } else {
            coords.extend_from_slice(&p.coords);
        }
        if coords.len() > max {
            return None;
        }
        if let Some(end) = p.end {
            coords.shrink_to_fit();
            return Some((coords, dim, end));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The doubles serde_json reads for the numbers of `text`, a JSON array.
    fn serde(text: &str) -> Option<Vec<f64>> {
        serde_json::from_str::<Vec<f64>>(text).ok()
    }

    fn fast(text: &str) -> Option<Vec<f64>> {
        let b = text.as_bytes();
        match parse_array(b, 0, Kind::Numbers { max: usize::MAX }) {
            Some((Parsed::Numbers(v), end)) if skip_ws(b, end) == b.len() => Some(v),
            _ => None,
        }
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// Every literal the fast path accepts reads as serde_json reads it, bit for bit; what it
    /// refuses, serde_json refuses too or reads (the slow path then).
    #[test]
    fn numbers_are_serde_jsons_bit_for_bit() {
        let literals = [
            "0",
            "-0",
            "0.0",
            "-0.0",
            "1",
            "-1",
            "0.1",
            "1e5",
            "1E5",
            "1e+5",
            "1e-5",
            "1.5E-05",
            "-0e0",
            "-0e-0",
            "123456789012345678",
            "18446744073709551615",
            "18446744073709551616",
            "-9223372036854775808",
            "-9223372036854775809",
            "123456789012345678901234567890",
            "9007199254740993",
            "1.6610155726440161",
            "1.067051959704762",
            "2.2250738585072014e-308",
            "2.2250738585072011e-308",
            "4.9406564584124654e-324",
            "5e-324",
            "2e-324",
            "1e-400",
            "-1e-400",
            "1.7976931348623157e308",
            "1.7976931348623158e308",
            "0.30000000000000004",
            "3.141592653589793238462643383279502884197",
            "1e0",
            "1e-0",
            "0e999",
            "1e022",
            "2.47032822920623272088e-324",
            "7.2057594037927933e16",
            "1.00000000000000011102230246251565404236316680908203125",
            "1.00000000000000011102230246251565404236316680908203124",
            "1.00000000000000011102230246251565404236316680908203126",
        ];
        for l in literals {
            let text = format!("[{l}]");
            let want = serde(&text).unwrap_or_else(|| panic!("serde refuses {l}"));
            if let Some(got) = fast(&text) {
                assert_eq!(bits(&got), bits(&want), "{l}");
            }
            // All of these are ordinary JSON: the fast path must take them (else it is no
            // fast path for them).
            assert!(fast(&text).is_some(), "{l} left to serde_json");
        }
        for bad in [
            "01",
            "-01",
            "1.",
            ".5",
            "-.5",
            "+1",
            "1e",
            "1e+",
            "--1",
            "inf",
            "-inf",
            "NaN",
            "Infinity",
            "1e400",
            "-1e400",
            "1.7976931348623159e308",
            "0x10",
            "1_0",
            "1.5.5",
            "\"1\"",
            "null",
            "true",
            "1 2",
            "",
        ] {
            let text = format!("[{bad}]");
            assert!(fast(&text).is_none(), "{bad} taken by the fast path");
        }
    }

    /// Random literals of every shape: digits of any length, exponents near the ends of the
    /// range, subnormals, integers.
    #[test]
    fn random_literals_are_serde_jsons_bit_for_bit() {
        let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut texts = Vec::new();
        for _ in 0..20_000 {
            let r = next();
            let mut l = String::new();
            if r & 1 == 1 {
                l.push('-');
            }
            let digits = 1 + (r >> 1) as usize % 25;
            let mut first = true;
            for _ in 0..digits {
                let d = (next() % 10) as u8;
                l.push(char::from(
                    b'0' + if first && digits > 1 { d.max(1) } else { d },
                ));
                first = false;
            }
            match (r >> 8) % 4 {
                0 => {}
                1 => {
                    l.push('.');
                    for _ in 0..1 + (r >> 12) % 20 {
                        l.push(char::from(b'0' + (next() % 10) as u8));
                    }
                }
                _ => {
                    if (r >> 16) % 2 == 0 {
                        l.push('.');
                        l.push(char::from(b'0' + (next() % 10) as u8));
                    }
                    l.push(if (r >> 17) % 2 == 0 { 'e' } else { 'E' });
                    let e = (next() % 660) as i64 - 340;
                    l.push_str(&e.to_string());
                }
            }
            texts.push(l);
        }
        // Shortest round trips of random doubles (what the command line writes).
        for _ in 0..20_000 {
            let x = f64::from_bits(next());
            if x.is_finite() {
                texts.push(zmij::Buffer::new().format_finite(x).to_string());
            }
        }
        let mut taken = 0;
        for l in &texts {
            let text = format!("[{l}]");
            match (fast(&text), serde(&text)) {
                (Some(got), Some(want)) => {
                    assert_eq!(bits(&got), bits(&want), "{l}");
                    taken += 1;
                }
                (Some(got), None) => panic!("{l}: fast {got:?}, serde_json refuses"),
                (None, _) => {}
            }
        }
        assert!(taken > texts.len() * 9 / 10, "{taken} of {}", texts.len());
    }

    fn rows(text: &str) -> Option<(Vec<f64>, usize)> {
        let b = text.as_bytes();
        rows_parallel(b, 0, usize::MAX).map(|(c, d, end)| {
            assert_eq!(skip_ws(b, end), b.len());
            (c, d)
        })
    }

    #[test]
    fn rows_parse_in_pieces_as_whole() {
        let n = 60_000;
        let text = format!(
            "[{}]",
            (0..n)
                .map(|i| format!("[{}, {}e-3 ]", i, i as f64 * 0.37))
                .collect::<Vec<_>>()
                .join(" ,\n")
        );
        assert!(text.len() > PARALLEL_BYTES);
        let (c, d) = rows(&text).unwrap();
        assert_eq!(d, 2);
        let want: Vec<Vec<f64>> = serde_json::from_str(&text).unwrap();
        assert_eq!(bits(&c), bits(&want.concat()));
        // A later row of another length, or anything but a number, anywhere: refused.
        for (at, with) in [
            ("[59999, ", "[59999, 1, "),
            ("[30001, ", "[\"x\", "),
            ("[2, ", "[2, null, "),
        ] {
            assert!(rows(&text.replacen(at, with, 1)).is_none(), "{with}");
        }
        assert!(rows("[[1], []]").is_none());
        assert!(rows("[]").is_none());
        assert_eq!(rows("[[1]]").unwrap(), (vec![1.0], 1));
        assert!(rows_parallel(b"[[1, 2], [3, 4]]", 0, 3).is_none());
    }

    /// A short array followed by a long string holding what looks like rows: the cut falls
    /// outside the array and is not used.
    #[test]
    fn a_cut_past_the_array_is_not_used() {
        let tail = "],[9,9".repeat(PARALLEL_BYTES / 6 + 10);
        let text = format!("[[1, 2], [3, 4]], \"{tail}\"");
        let (c, d, end) = rows_parallel(text.as_bytes(), 0, usize::MAX).unwrap();
        assert_eq!((c, d), (vec![1.0, 2.0, 3.0, 4.0], 2));
        assert_eq!(&text[end..end + 1], ",");
    }
}
