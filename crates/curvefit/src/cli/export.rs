//! `--export FILE` of `curvefit refine`: the refinement's limit curve (docs/limit.md) in the format
//! the file's extension (or `--export-format`) names; the text comes from [`crate::export`], and
//! the file is one more output of the command's all-or-nothing commit.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::export::ExportFormat;
use crate::spec::InputError;

/// The export flags (shown under their own heading in `--help`).
#[derive(Args, Debug, Clone, Default)]
#[command(next_help_heading = "Export (refine)")]
pub struct ExportArgs {
    /// Write the limit curve (the cubic spline the refinement tends to, docs/limit.md) here:
    /// .csv samples u,x,y\[,z\]; .svg an SVG path of exact cubic Béziers (plane curves); .dxf a DXF
    /// SPLINE of degree 3; .json degree, knots, control points, Bézier pieces.
    #[arg(long = "export", value_name = "FILE")]
    pub export_file: Option<PathBuf>,
    /// The export format when the file's extension does not say it (csv, svg, dxf, json).
    #[arg(long = "export-format", value_name = "FORMAT", value_parser = ["csv", "svg", "dxf", "json"])]
    pub export_format: Option<String>,
    /// CSV export: this many samples evenly in the parameter interval [default: 16 per piece,
    /// every break included].
    #[arg(long = "samples", value_name = "N")]
    pub samples: Option<usize>,
}

impl ExportArgs {
    /// The format: `--export-format`, else the extension of `path`.
    ///
    /// # Errors
    /// When neither names a format, or `--samples` is given for another format than csv.
    pub fn format(&self, path: &Path) -> Result<ExportFormat, InputError> {
        let named = match &self.export_format {
            Some(f) => ExportFormat::from_name(f),
            None => path
                .extension()
                .and_then(|e| e.to_str())
                .and_then(ExportFormat::from_name),
        };
        let format = named.ok_or_else(|| {
            InputError::new(
                "--export",
                format!(
                    "cannot tell the format of {} from its extension: name the file .csv, .svg, .dxf or .json, or give --export-format",
                    path.display()
                ),
            )
        })?;
        if self.samples.is_some() && format != ExportFormat::Csv {
            return Err(InputError::new(
                "--samples",
                "applies to a CSV export only (the other formats are exact)",
            ));
        }
        Ok(format)
    }

    /// Refuses export flags without `--export FILE`.
    ///
    /// # Errors
    /// `--export-format` or `--samples` given alone.
    pub fn check(&self) -> Result<(), InputError> {
        if self.export_file.is_none() {
            if self.export_format.is_some() {
                return Err(InputError::new("--export-format", "needs --export FILE"));
            }
            if self.samples.is_some() {
                return Err(InputError::new("--samples", "needs --export FILE"));
            }
        }
        Ok(())
    }
}
