//! Output formats of the JSON subcommands (`--format json|csv|npy`).
//!
//! - `json` (default): the whole result, as [`crate::spec`] defines it.
//! - `csv`: the result's main array ([`Table`]), one row per line, a header line with the column
//!   names, numbers as their shortest round-trip decimal (the same digits as the JSON).
//! - `npy`: the same array as a NumPy `.npy` file (version 1.0, little-endian float64, C order,
//!   shape (rows, columns)): `numpy.load(file)` reads it, with no parsing.
//!
//! `csv` and `npy` carry only the array (no energy, certificate or counts): they are for large
//! outputs, where printing and parsing the JSON would cost more than the solve. Without
//! `--format`, an `-o` file ending in `.csv` or `.npy` selects that format.
//!
//! Large text outputs are formatted in pieces on every core while the calling thread writes the
//! finished pieces in order ([`write_pieces`]); `.npy` is the doubles' bytes, handed to the
//! output 1 MiB at a time.

use std::io::Write;
use std::path::Path;

use serde::Serialize;

use super::InputError;

/// An output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// The whole JSON result.
    Json,
    /// The result's main array as CSV with a header line.
    Csv,
    /// The result's main array as a NumPy .npy file (float64).
    Npy,
}

impl Format {
    /// `--format`, else the `-o` file's extension (`.csv`, `.npy`), else JSON.
    pub fn choose(flag: Option<Format>, output: Option<&Path>) -> Format {
        if let Some(f) = flag {
            return f;
        }
        match output
            .and_then(|p| p.extension())
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("csv") => Format::Csv,
            Some("npy") => Format::Npy,
            _ => Format::Json,
        }
    }
}

/// A result's main array: `rows × columns` numbers, row-major, with column names.
pub struct Table<'a> {
    /// Column names (the CSV header).
    pub columns: Vec<String>,
    /// The numbers, row-major (`data.len()` is a multiple of `columns.len()`).
    pub data: std::borrow::Cow<'a, [f64]>,
}

impl Table<'_> {
    /// Column names for points of dimension `d`: `x, y, z` up to 3, else `x1 … xd`.
    pub fn point_columns(d: usize) -> Vec<String> {
        if d <= 3 {
            ["x", "y", "z"][..d].iter().map(|s| s.to_string()).collect()
        } else {
            (1..=d).map(|i| format!("x{i}")).collect()
        }
    }
}

/// Rows formatted per piece (one thread's task; a piece of 16384 rows of two numbers is
/// ~700 kB of text).
const ROWS_PER_CHUNK: usize = 1 << 14;

/// Bytes of the float64 data handed to the output per write.
const NPY_CHUNK: usize = 1 << 20;

/// One piece of an output: bytes appended to the given (empty) buffer on a formatting thread.
pub type Piece<'a> = Box<dyn FnOnce(&mut Vec<u8>) -> std::io::Result<()> + Send + 'a>;

/// A piece of fixed bytes.
pub fn bytes_piece<'a>(bytes: &'a [u8]) -> Piece<'a> {
    Box::new(move |out: &mut Vec<u8>| {
        out.extend_from_slice(bytes);
        Ok(())
    })
}

/// Pieces a formatting thread may run ahead of the writer.
const AHEAD: usize = 2;

/// Writes `pieces` in order, making them on every core while the calling thread writes: piece
/// k is made by thread k mod T, each thread at most `AHEAD` pieces ahead of the writer, into
/// buffers the writer hands back once written. Formatting floats (~30 ns a number, shortest
/// round trip) is the cost of a large text output; with the writes overlapped, a text output
/// takes about (formatting + copying into the file) / cores, and its memory is a few pieces per
/// thread, touched once (a fresh buffer per piece cost a page fault per 4 KiB of text).
///
/// # Errors
/// The first error of a piece or of the output.
pub fn write_pieces(pieces: Vec<Piece<'_>>, out: &mut dyn Write) -> std::io::Result<()> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get().min(16))
        .min(pieces.len());
    if threads <= 1 {
        let mut buf = Vec::new();
        for p in pieces {
            buf.clear();
            p(&mut buf)?;
            out.write_all(&buf)?;
        }
        return Ok(());
    }
    let n = pieces.len();
    let mut queues: Vec<Vec<Piece<'_>>> = (0..threads).map(|_| Vec::new()).collect();
    for (k, p) in pieces.into_iter().enumerate() {
        queues[k % threads].push(p);
    }
    std::thread::scope(|s| {
        let mut workers = Vec::with_capacity(threads);
        for queue in queues {
            let (tx, rx) = std::sync::mpsc::sync_channel::<std::io::Result<Vec<u8>>>(AHEAD);
            let (back, recycled) = std::sync::mpsc::channel::<Vec<u8>>();
            s.spawn(move || {
                for p in queue {
                    let mut buf = recycled.try_recv().unwrap_or_default();
                    buf.clear();
                    let made = p(&mut buf).map(|()| buf);
                    // The writer stopped (an error): nothing more is wanted.
                    if tx.send(made).is_err() {
                        return;
                    }
                }
            });
            workers.push((rx, back));
        }
        for k in 0..n {
            let (rx, back) = &workers[k % threads];
            let bytes = rx
                .recv()
                .map_err(|_| std::io::Error::other("a formatting thread failed"))??;
            out.write_all(&bytes)?;
            // The worker may have finished its queue: then the buffer is simply dropped.
            let _ = back.send(bytes);
        }
        Ok(())
    })
}

/// Writes `value` as one line of JSON.
///
/// # Errors
/// The output's write errors.
pub fn write_json(value: &impl Serialize, out: &mut dyn Write) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::with_capacity(1 << 18, out);
    serde_json::to_writer(&mut w, value).map_err(std::io::Error::other)?;
    w.write_all(b"\n")?;
    w.flush()
}

/// One number as the JSON and CSV outputs write it: the shortest decimal that reads back as
/// `x` (zmij), `null` (JSON) or `NaN`/`inf` (CSV) when not finite.
#[inline]
fn number(out: &mut Vec<u8>, num: &mut zmij::Buffer, x: f64, json: bool) {
    if x.is_finite() {
        out.extend_from_slice(num.format_finite(x).as_bytes());
    } else if json {
        out.extend_from_slice(b"null");
    } else {
        out.extend_from_slice(num.format(x).as_bytes());
    }
}

/// Rows of a CSV: `x,y\n` each.
fn csv_chunk(out: &mut Vec<u8>, data: &[f64], columns: usize) {
    out.reserve(data.len() * 20);
    let mut num = zmij::Buffer::new();
    for row in data.chunks_exact(columns) {
        for (j, &x) in row.iter().enumerate() {
            if j > 0 {
                out.push(b',');
            }
            number(out, &mut num, x, false);
        }
        out.push(b'\n');
    }
}

/// Writes `table` as CSV: a header line, then one row per line, formatted on every core
/// ([`write_pieces`]).
///
/// # Errors
/// The output's write errors.
pub fn write_csv(table: &Table<'_>, out: &mut dyn Write) -> std::io::Result<()> {
    let header = table.columns.join(",") + "\n";
    let c = table.columns.len().max(1);
    let mut pieces: Vec<Piece<'_>> = vec![bytes_piece(header.as_bytes())];
    for chunk in table.data.chunks(ROWS_PER_CHUNK * c) {
        pieces.push(Box::new(move |out: &mut Vec<u8>| {
            csv_chunk(out, chunk, c);
            Ok(())
        }));
    }
    write_pieces(pieces, out)
}

/// Writes `table` as a NumPy `.npy` file, version 1.0: the magic string, a little-endian u16
/// header length, the header dictionary padded with spaces to a multiple of 64 bytes (ending in a
/// newline), then the float64 data in C order, handed to the output 1 MiB at a time.
///
/// # Errors
/// The output's write errors.
pub fn write_npy(table: &Table<'_>, out: &mut dyn Write) -> std::io::Result<()> {
    let c = table.columns.len().max(1);
    let rows = table.data.len() / c;
    let mut header =
        format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({rows}, {c}), }}");
    // magic (6) + version (2) + length (2) + header + '\n' ≡ 0 (mod 64)
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let len = u16::try_from(header.len()).map_err(std::io::Error::other)?;
    let mut head = b"\x93NUMPY\x01\x00".to_vec();
    head.extend_from_slice(&len.to_le_bytes());
    head.extend_from_slice(header.as_bytes());
    out.write_all(&head)?;
    let mut buf = Vec::with_capacity(NPY_CHUNK.min(8 * table.data.len()));
    for chunk in table.data.chunks(NPY_CHUNK / 8) {
        buf.clear();
        buf.resize(8 * chunk.len(), 0);
        for (b, x) in buf.chunks_exact_mut(8).zip(chunk) {
            b.copy_from_slice(&x.to_le_bytes());
        }
        out.write_all(&buf)?;
    }
    Ok(())
}

/// One chunk of a JSON array: rows `[x,y]` (`dim` ≥ 1) or numbers (`dim` = 0), comma-separated,
/// each number as serde_json writes it (shortest round trip, `null` if not finite).
fn json_chunk(out: &mut Vec<u8>, data: &[f64], dim: usize, lead: u8) {
    out.reserve(data.len() * 24 + 1);
    let mut num = zmij::Buffer::new();
    out.push(lead);
    if dim == 0 {
        for (i, &x) in data.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            number(out, &mut num, x, true);
        }
    } else {
        for (i, row) in data.chunks_exact(dim).enumerate() {
            out.extend_from_slice(if i > 0 { b",[" } else { b"[" });
            for (j, &x) in row.iter().enumerate() {
                if j > 0 {
                    out.push(b',');
                }
                number(out, &mut num, x, true);
            }
            out.push(b']');
        }
    }
}

/// The pieces of a JSON array of `data` — rows of `dim` numbers (`[[x,y],…]`), or for `dim` = 0
/// the numbers themselves — byte for byte as serde_json would write it, in chunks of 16384 rows
/// for [`write_pieces`].
pub fn json_array_pieces(data: &[f64], dim: usize) -> Vec<Piece<'_>> {
    let per_row = dim.max(1);
    let mut pieces: Vec<Piece<'_>> = data
        .chunks(ROWS_PER_CHUNK * per_row)
        .enumerate()
        .map(|(k, chunk)| -> Piece<'_> {
            let lead = if k == 0 { b'[' } else { b',' };
            Box::new(move |out: &mut Vec<u8>| {
                json_chunk(out, chunk, dim, lead);
                Ok(())
            })
        })
        .collect();
    pieces.push(bytes_piece(if data.is_empty() { b"[]" } else { b"]" }));
    pieces
}

/// Writes a JSON array of `data` ([`json_array_pieces`]) formatted on every core.
///
/// # Errors
/// The output's write errors.
pub fn write_json_array(data: &[f64], dim: usize, out: &mut dyn Write) -> std::io::Result<()> {
    write_pieces(json_array_pieces(data, dim), out)
}

/// The writer of a result in `format`: `json` writes the whole result, `table` is its main array
/// (`None` when the command has none: only JSON then).
///
/// # Errors
/// `--format` csv/npy for a command without an array.
pub fn writer<'a>(
    format: Format,
    json: super::Writer<'a>,
    table: Option<Table<'a>>,
    name: &str,
) -> Result<super::Writer<'a>, InputError> {
    Ok(match (format, table) {
        (Format::Json, _) => json,
        (Format::Csv, Some(t)) => Box::new(move |w: &mut dyn Write| write_csv(&t, w)),
        (Format::Npy, Some(t)) => Box::new(move |w: &mut dyn Write| write_npy(&t, w)),
        (f, None) => {
            return Err(InputError::new(
                "--format",
                format!("`{name}` writes only JSON, not {f:?}").to_lowercase(),
            ))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> Table<'static> {
        Table {
            columns: Table::point_columns(2),
            data: vec![0.0, 1.5, -2.25, 1e-7].into(),
        }
    }

    #[test]
    fn csv_has_a_header_and_round_trip_numbers() {
        let mut out = Vec::new();
        write_csv(&table(), &mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "x,y\n0.0,1.5\n-2.25,1e-7\n"
        );
    }

    #[test]
    fn npy_header_is_aligned_and_data_little_endian() {
        let mut out = Vec::new();
        write_npy(&table(), &mut out).unwrap();
        assert_eq!(&out[..8], b"\x93NUMPY\x01\x00");
        let hlen = u16::from_le_bytes([out[8], out[9]]) as usize;
        assert_eq!((10 + hlen) % 64, 0);
        let header = std::str::from_utf8(&out[10..10 + hlen]).unwrap();
        assert!(header.contains("'shape': (2, 2)") && header.ends_with('\n'));
        let data: Vec<f64> = out[10 + hlen..]
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(data, [0.0, 1.5, -2.25, 1e-7]);
    }

    #[test]
    fn parallel_json_arrays_are_serde_json_byte_for_byte() {
        let mut s: u64 = 3;
        let data: Vec<f64> = (0..3 * ROWS_PER_CHUNK * 2 + 7)
            .map(|i| {
                s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                match i % 97 {
                    0 => f64::NAN,
                    1 => 1e300,
                    2 => -0.0,
                    3 => 3.0,
                    _ => (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5,
                }
            })
            .collect();
        let rows: Vec<&[f64]> = data.chunks_exact(2).collect();
        let mut fast = Vec::new();
        write_json_array(&data[..rows.len() * 2], 2, &mut fast).unwrap();
        assert_eq!(fast, serde_json::to_vec(&rows).unwrap());
        let mut fast = Vec::new();
        write_json_array(&data, 0, &mut fast).unwrap();
        assert_eq!(fast, serde_json::to_vec(&data).unwrap());
        let mut fast = Vec::new();
        write_json_array(&[], 3, &mut fast).unwrap();
        assert_eq!(fast, b"[]");
    }

    /// CSV of many pieces, non-finite values included, equals the rows formatted one by one
    /// (the previous, sequential writer).
    #[test]
    fn parallel_csv_is_the_rows_one_by_one() {
        let data: Vec<f64> = (0..3 * 3 * ROWS_PER_CHUNK + 6)
            .map(|i| match i % 101 {
                0 => f64::NAN,
                1 => f64::NEG_INFINITY,
                2 => -0.0,
                _ => (i as f64).sqrt() * 1e-3 - 7.0,
            })
            .collect();
        let table = Table {
            columns: Table::point_columns(3),
            data: data.as_slice().into(),
        };
        let mut fast = Vec::new();
        write_csv(&table, &mut fast).unwrap();
        let mut want = String::from("x,y,z\n");
        let mut num = zmij::Buffer::new();
        for row in data.chunks_exact(3) {
            let cells: Vec<String> = row.iter().map(|&x| num.format(x).to_string()).collect();
            want.push_str(&cells.join(","));
            want.push('\n');
        }
        assert_eq!(String::from_utf8(fast).unwrap(), want);
    }

    /// A failing output or piece ends the write with its error (the formatting threads stop;
    /// nothing hangs).
    #[test]
    fn errors_stop_the_formatting_threads() {
        struct Full(usize);
        impl Write for Full {
            fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
                if b.len() > self.0 {
                    return Err(std::io::Error::other("full"));
                }
                self.0 -= b.len();
                Ok(b.len())
            }
            fn flush(&mut self) -> std::io::Result<()> {
                Ok(())
            }
        }
        let data = vec![0.5; 40 * ROWS_PER_CHUNK];
        let e = write_json_array(&data, 2, &mut Full(1 << 20)).unwrap_err();
        assert_eq!(e.to_string(), "full");
        let pieces: Vec<Piece<'_>> = vec![
            bytes_piece(b"a"),
            Box::new(|_: &mut Vec<u8>| Err(std::io::Error::other("bad"))),
            bytes_piece(b"c"),
        ];
        let mut out = Vec::new();
        assert_eq!(
            write_pieces(pieces, &mut out).unwrap_err().to_string(),
            "bad"
        );
        assert_eq!(out, b"a");
    }

    #[test]
    fn the_extension_chooses_the_format() {
        assert_eq!(Format::choose(None, Some(Path::new("a.CSV"))), Format::Csv);
        assert_eq!(Format::choose(None, Some(Path::new("a.npy"))), Format::Npy);
        assert_eq!(
            Format::choose(None, Some(Path::new("a.json"))),
            Format::Json
        );
        assert_eq!(
            Format::choose(Some(Format::Json), Some(Path::new("a.npy"))),
            Format::Json
        );
        assert_eq!(Format::choose(None, None), Format::Json);
    }
}
