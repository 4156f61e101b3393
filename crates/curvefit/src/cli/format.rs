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
//! Every writer fills a contiguous chunk buffer and hands it to the output 256 KiB at a time: the
//! serializer's many small writes (a comma, a number) are inlined appends instead of calls
//! through a `dyn Write`.

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

/// Chunk size handed to the output.
const CHUNK: usize = 1 << 18;

/// A writer that appends to a chunk and hands full chunks to `out`.
struct Chunked<'a> {
    buf: Vec<u8>,
    out: &'a mut dyn Write,
}

impl Write for Chunked<'_> {
    #[inline]
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        self.write_all(data)?;
        Ok(data.len())
    }
    #[inline]
    fn write_all(&mut self, data: &[u8]) -> std::io::Result<()> {
        if self.buf.len() + data.len() > CHUNK {
            self.out.write_all(&self.buf)?;
            self.buf.clear();
        }
        self.buf.extend_from_slice(data);
        Ok(())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.out.write_all(&self.buf)?;
        self.buf.clear();
        self.out.flush()
    }
}

fn chunked(out: &mut dyn Write) -> Chunked<'_> {
    Chunked {
        buf: Vec::with_capacity(CHUNK),
        out,
    }
}

/// Writes `value` as one line of JSON.
///
/// # Errors
/// The output's write errors.
pub fn write_json(value: &impl Serialize, out: &mut dyn Write) -> std::io::Result<()> {
    let mut w = chunked(out);
    serde_json::to_writer(&mut w, value).map_err(std::io::Error::other)?;
    w.write_all(b"\n")?;
    w.flush()
}

/// Writes `table` as CSV: a header line, then one row per line.
///
/// # Errors
/// The output's write errors.
pub fn write_csv(table: &Table<'_>, out: &mut dyn Write) -> std::io::Result<()> {
    let mut w = chunked(out);
    w.write_all(table.columns.join(",").as_bytes())?;
    w.write_all(b"\n")?;
    let c = table.columns.len().max(1);
    let mut num = zmij::Buffer::new();
    for row in table.data.chunks_exact(c) {
        for (j, &x) in row.iter().enumerate() {
            if j > 0 {
                w.write_all(b",")?;
            }
            w.write_all(num.format(x).as_bytes())?;
        }
        w.write_all(b"\n")?;
    }
    w.flush()
}

/// Writes `table` as a NumPy `.npy` file, version 1.0: the magic string, a little-endian u16
/// header length, the header dictionary padded with spaces to a multiple of 64 bytes (ending in a
/// newline), then the float64 data in C order.
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
    let mut w = chunked(out);
    w.write_all(b"\x93NUMPY\x01\x00")?;
    let len = u16::try_from(header.len()).map_err(std::io::Error::other)?;
    w.write_all(&len.to_le_bytes())?;
    w.write_all(header.as_bytes())?;
    for x in table.data.iter() {
        w.write_all(&x.to_le_bytes())?;
    }
    w.flush()
}

/// Rows formatted per chunk (one thread's share of a wave).
const ROWS_PER_CHUNK: usize = 1 << 14;

/// One chunk of a JSON array: rows `[x,y]` (`dim` ≥ 1) or numbers (`dim` = 0), comma-separated,
/// each number as serde_json writes it (shortest round trip, `null` if not finite).
fn json_chunk(data: &[f64], dim: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() * 24);
    let mut num = zmij::Buffer::new();
    let mut number = |out: &mut Vec<u8>, x: f64| {
        if x.is_finite() {
            out.extend_from_slice(num.format_finite(x).as_bytes());
        } else {
            out.extend_from_slice(b"null");
        }
    };
    if dim == 0 {
        for (i, &x) in data.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            number(&mut out, x);
        }
    } else {
        for (i, row) in data.chunks_exact(dim).enumerate() {
            out.extend_from_slice(if i > 0 { b",[" } else { b"[" });
            for (j, &x) in row.iter().enumerate() {
                if j > 0 {
                    out.push(b',');
                }
                number(&mut out, x);
            }
            out.push(b']');
        }
    }
    out
}

/// Writes a JSON array of `data` — rows of `dim` numbers (`[[x,y],…]`), or for `dim` = 0 the
/// numbers themselves — byte for byte as serde_json would, formatting chunks of 16384 rows on
/// every core in waves (shortest round-trip formatting is the cost of a large JSON result:
/// ~30 ns a number); memory: one wave of chunks.
///
/// # Errors
/// The output's write errors.
pub fn write_json_array(data: &[f64], dim: usize, out: &mut dyn Write) -> std::io::Result<()> {
    let per_row = dim.max(1);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get().min(16));
    let chunks: Vec<&[f64]> = data.chunks(ROWS_PER_CHUNK * per_row).collect();
    out.write_all(b"[")?;
    for (w, wave) in chunks.chunks(threads).enumerate() {
        let bufs: Vec<Vec<u8>> = if wave.len() == 1 {
            vec![json_chunk(wave[0], dim)]
        } else {
            std::thread::scope(|s| {
                let handles: Vec<_> = wave
                    .iter()
                    .map(|c| s.spawn(move || json_chunk(c, dim)))
                    .collect();
                handles
                    .into_iter()
                    .map(|h| {
                        h.join()
                            .map_err(|_| std::io::Error::other("a formatting thread failed"))
                    })
                    .collect::<std::io::Result<Vec<_>>>()
            })?
        };
        for (i, b) in bufs.iter().enumerate() {
            if w > 0 || i > 0 {
                out.write_all(b",")?;
            }
            out.write_all(b)?;
        }
    }
    out.write_all(b"]")
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
