//! The density table's file format: a CSV with the header `height_m,extinction_per_m`
//! and one row per height, heights strictly increasing, extinctions ≥ 0 (per metre).
//! Blank lines and `#` comments are skipped. Errors name the file, the line and the value.

use super::table::DensityTable;
use crate::error::{Error, Result};
use std::path::Path;

/// The header the file must start with (after comments and blank lines).
pub const HEADER: &str = "height_m,extinction_per_m";

impl DensityTable {
    /// A table from a CSV file (module docs of `layered::csv`): `height_m,extinction_per_m`.
    pub fn from_csv(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = crate::io::limits::read_text(path)?;
        Self::parse_csv(&text, path)
    }

    /// [`DensityTable::from_csv`] on text already read; `path` names it in errors.
    pub fn parse_csv(text: &str, path: &Path) -> Result<Self> {
        let bad =
            |line: usize, detail: String| Error::format(path, format!("line {line}: {detail}"));
        // A byte-order mark would otherwise make the header look wrong.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut header_seen = false;
        let mut heights: Vec<f64> = Vec::new();
        let mut extinction = Vec::new();
        for (n, raw) in text.lines().enumerate() {
            let line = n + 1;
            let content = raw.split('#').next().unwrap_or("").trim();
            if content.is_empty() {
                continue;
            }
            let fields: Vec<&str> = content.split(',').map(str::trim).collect();
            if !header_seen {
                if fields != ["height_m", "extinction_per_m"] {
                    return Err(bad(
                        line,
                        format!("`{content}` is not the header; expected the first line to be `{HEADER}`"),
                    ));
                }
                header_seen = true;
                continue;
            }
            if fields.len() != 2 {
                return Err(bad(
                    line,
                    format!(
                        "{} fields in `{content}`; expected 2: {HEADER}",
                        fields.len()
                    ),
                ));
            }
            let number = |k: usize| {
                let name = ["height_m", "extinction_per_m"][k];
                match fields[k].parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(bad(
                        line,
                        format!("{name} = `{}` is not a finite number", fields[k]),
                    )),
                }
            };
            let (h, k) = (number(0)?, number(1)?);
            if let Some(&previous) = heights.last() {
                if h <= previous {
                    return Err(bad(
                        line,
                        format!(
                            "height_m = {h} is not above the previous row's {previous}; \
                             heights must increase strictly"
                        ),
                    ));
                }
            }
            if k < 0.0 {
                return Err(bad(
                    line,
                    format!("extinction_per_m = {k} is negative; expected ≥ 0"),
                ));
            }
            heights.push(h);
            extinction.push(k);
        }
        if !header_seen {
            return Err(Error::format(
                path,
                format!("empty: expected the header `{HEADER}` and at least 2 rows"),
            ));
        }
        if heights.len() < 2 {
            return Err(Error::format(
                path,
                format!(
                    "{} data row(s); expected at least 2 (height_m,extinction_per_m), \
                     linear between rows",
                    heights.len()
                ),
            ));
        }
        DensityTable::new(heights, extinction)
            .map_err(|e| Error::format(path, format!("not a usable density table: {e}")))
    }
}
