//! Spectral sensitivities q_c(λ) of a camera's channels (paper 002, eq. 7), on a fixed
//! wavelength grid, and the spectra needed to integrate against them.
//!
//! - [`Sensitivity::cie_srgb`], the default: the CIE 1931 2° standard observer by the
//!   multi-lobe analytic fit of Wyman, Sloan and Shirley (2013, "Simple Analytic
//!   Approximations to the CIE XYZ Color Matching Functions", JCGT 2(2), eq. 2-4),
//!   turned into linear sRGB by the IEC 61966-2-1 matrix ([`XYZ_TO_LINEAR_SRGB`]): the
//!   curves of an ideal camera whose raw values are linear sRGB. They have negative lobes
//!   (r below 0 over 460-550 nm, g over 390-470 and 610-680 nm, b beyond 515 nm); see
//!   [`crate::atmosphere`] for how the attenuation handles them.
//! - [`Sensitivity::from_csv`]: a camera's measured curves.
//!
//! All curves live on [`GRID_LEN`] samples, 380 to 780 nm every [`GRID_STEP_NM`] (the
//! range of eq. 7 and 11), and integrals over them use the composite Simpson rule
//! ([`simpson_weights`]).

use crate::error::{Error, Result};
use std::path::Path;

/// First wavelength of the grid (nm).
pub const GRID_START_NM: f64 = 380.0;
/// Last wavelength of the grid (nm).
pub const GRID_END_NM: f64 = 780.0;
/// Grid step (nm).
pub const GRID_STEP_NM: f64 = 1.0;
/// Samples on the grid: 401, an even number (400) of Simpson intervals.
pub const GRID_LEN: usize = 401;

/// The wavelength (nm) of grid sample `i`.
pub fn grid_wavelength_nm(i: usize) -> f64 {
    GRID_START_NM + i as f64 * GRID_STEP_NM
}

/// The composite Simpson weights of the grid (h/3 · 1, 4, 2, 4, …, 4, 1; units nm), so
/// that Σ wᵢ·f(λᵢ) ≈ ∫ f dλ over 380-780 nm. On the CIE fit times D65 times the
/// attenuation, the 1 nm rule is within 1e-8 of a 0.05 nm one in every Γ_c (the
/// trapezoid rule is within about 1e-6).
pub fn simpson_weights() -> Vec<f64> {
    (0..GRID_LEN)
        .map(|i| {
            let w = if i == 0 || i == GRID_LEN - 1 {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * GRID_STEP_NM / 3.0
        })
        .collect()
}

/// A camera channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// Red.
    R,
    /// Green.
    G,
    /// Blue.
    B,
}

impl Channel {
    /// r, g, b.
    pub const ALL: [Channel; 3] = [Channel::R, Channel::G, Channel::B];

    /// 0, 1, 2: the channel's row in tables and its index in RGB arrays.
    pub fn index(self) -> usize {
        match self {
            Channel::R => 0,
            Channel::G => 1,
            Channel::B => 2,
        }
    }

    /// `r`, `g` or `b`.
    pub fn name(self) -> &'static str {
        ["r", "g", "b"][self.index()]
    }
}

/// One lobe of the Wyman-Sloan-Shirley fit: a Gaussian with a different width on each side
/// of its peak `mu`.
fn lobe(lambda_nm: f64, mu: f64, sigma_below: f64, sigma_above: f64) -> f64 {
    let t = (lambda_nm - mu)
        / if lambda_nm < mu {
            sigma_below
        } else {
            sigma_above
        };
    (-0.5 * t * t).exp()
}

/// The CIE 1931 2° colour matching functions (x̄, ȳ, z̄) at `lambda_nm`, by the multi-lobe
/// piecewise-Gaussian fit of Wyman, Sloan and Shirley (2013, JCGT 2(2), eq. 2-4). The fit
/// is within a few per cent of the tabulated functions where they matter; its far tails
/// (beyond 700 nm) are less faithful.
pub fn cie_1931_xyz(lambda_nm: f64) -> [f64; 3] {
    let l = lambda_nm;
    [
        1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7)
            - 0.065 * lobe(l, 501.1, 20.4, 26.2),
        0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1),
        1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8),
    ]
}

/// CIE XYZ to linear sRGB (D65 white), rows r, g, b: the matrix of IEC 61966-2-1:1999.
/// A D65 spectrum maps to r = g = b.
pub const XYZ_TO_LINEAR_SRGB: [[f64; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

/// CIE standard illuminant D65, relative spectral power at 5 nm from 380 to 780 nm
/// (CIE 015, 100 at 560 nm).
const D65_5NM: [f64; 81] = [
    49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204, 91.486, 92.4589, 93.4318, 90.057,
    86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392,
    115.923, 112.367, 108.811, 109.082, 109.354, 108.578, 107.802, 106.296, 104.79, 106.239,
    107.689, 106.047, 104.405, 104.225, 104.046, 102.023, 100.0, 98.1671, 96.3342, 96.0611, 95.788,
    92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936, 83.2886,
    83.4939, 83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281, 78.2842,
    74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863,
    75.087, 69.3398, 63.5927, 55.0054, 46.4182, 56.6118, 66.8054, 65.0941, 63.3828,
];

/// The spectrum of the light whose attenuation Γ_c measures (the weight of eq. 11's
/// integrals besides q_c).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Illuminant {
    /// A flat spectrum: eq. 11 as printed.
    EqualEnergy,
    /// CIE D65 daylight, linearly interpolated from its 5 nm table (as CIE 015
    /// recommends for the D illuminants): a grey surface in daylight. The default, since
    /// it is the white of sRGB, so Γ_c is then exact for every neutral surface in every
    /// channel of the default camera.
    #[default]
    D65,
}

impl Illuminant {
    /// Relative spectral power at `lambda_nm` (0 outside 380-780 nm for D65).
    pub fn power(self, lambda_nm: f64) -> f64 {
        match self {
            Illuminant::EqualEnergy => 1.0,
            Illuminant::D65 => {
                let x = (lambda_nm - GRID_START_NM) / 5.0;
                if !(0.0..=80.0).contains(&x) {
                    return 0.0;
                }
                let i = (x.floor() as usize).min(79);
                let f = x - i as f64;
                D65_5NM[i] * (1.0 - f) + D65_5NM[i + 1] * f
            }
        }
    }
}

/// The three spectral sensitivities q_r, q_g, q_b of a camera, sampled on the fixed grid
/// (380-780 nm, see [`GRID_LEN`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Sensitivity {
    curves: [Vec<f64>; 3],
}

impl Default for Sensitivity {
    fn default() -> Self {
        Sensitivity::cie_srgb()
    }
}

/// Where a row of sensitivity data came from, for error messages.
enum Origin<'a> {
    File { path: &'a Path, lines: &'a [usize] },
    Samples,
}

impl Origin<'_> {
    /// An error about row `row` (None: the data as a whole).
    fn error(&self, row: Option<usize>, detail: String) -> Error {
        match self {
            Origin::File { path, lines } => match row {
                Some(r) => Error::format(*path, format!("line {}: {detail}", lines[r])),
                None => Error::format(*path, detail),
            },
            Origin::Samples => Error::invalid(
                "sensitivity",
                match row {
                    Some(r) => format!("row {r}: {detail}"),
                    None => detail,
                },
                "finite samples in increasing wavelength, overlapping 380-780 nm, \
                 each channel responding positively to a flat spectrum",
            ),
        }
    }
}

impl Sensitivity {
    /// The default camera: the CIE 1931 2° observer (Wyman-Sloan-Shirley fit) times
    /// [`XYZ_TO_LINEAR_SRGB`], signed curves whose response to D65 is r = g = b.
    pub fn cie_srgb() -> Self {
        Sensitivity::cie_in(XYZ_TO_LINEAR_SRGB)
    }

    /// The CIE 1931 2° observer in linear RGB of other primaries, `xyz_to_rgb` (rows r, g,
    /// b): the ideal camera whose raw values are a photo's own linear RGB, such as Display
    /// P3's ([`crate::io::colour_profile::ColourProfile::xyz_to_rgb`]).
    pub fn cie_in(xyz_to_rgb: [[f64; 3]; 3]) -> Self {
        let mut curves = [
            vec![0.0; GRID_LEN],
            vec![0.0; GRID_LEN],
            vec![0.0; GRID_LEN],
        ];
        for i in 0..GRID_LEN {
            let xyz = cie_1931_xyz(grid_wavelength_nm(i));
            for (curve, row) in curves.iter_mut().zip(xyz_to_rgb) {
                curve[i] = row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2];
            }
        }
        Sensitivity { curves }
    }

    /// A camera's measured curves from a CSV file: one row per wavelength,
    /// `lambda_nm,r,g,b`, wavelengths strictly increasing; an optional header line;
    /// `#` starts a comment. The curves are resampled onto the grid by linear
    /// interpolation and are zero outside the rows' range, which must overlap 380-780 nm.
    /// Values may be negative (noise, colour-matching curves) but each channel must
    /// respond positively to a flat spectrum. Errors name the file, the line and the value.
    pub fn from_csv(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = crate::io::limits::read_text(path)?;
        Self::parse_csv(&text, path)
    }

    /// [`Sensitivity::from_csv`] on text already read; `path` names it in errors.
    pub fn parse_csv(text: &str, path: &Path) -> Result<Self> {
        let mut rows = Vec::new();
        let mut lines = Vec::new();
        // A byte-order mark would otherwise make a first data row look like a header.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        for (n, raw) in text.lines().enumerate() {
            let line_no = n + 1;
            let content = raw.split('#').next().unwrap_or("").trim();
            if content.is_empty() {
                continue;
            }
            let fields: Vec<&str> = content.split(',').map(str::trim).collect();
            let numbers: Vec<Option<f64>> = fields.iter().map(|f| f.parse().ok()).collect();
            if rows.is_empty() && lines.is_empty() && numbers[0].is_none() {
                // The first line that is not a comment may be a header such as
                // `lambda_nm,r,g,b` (its first field is not a number); any later line
                // must be numbers, and so must a first line starting with one, so that
                // a typo in the first row is an error rather than a skipped header.
                lines.push(line_no);
                continue;
            }
            if fields.len() != 4 {
                return Err(Error::format(
                    path,
                    format!(
                        "line {line_no}: {} fields in `{content}`; expected 4: lambda_nm,r,g,b",
                        fields.len()
                    ),
                ));
            }
            let mut row = [0.0; 4];
            for (k, (field, number)) in fields.iter().zip(&numbers).enumerate() {
                row[k] = number.ok_or_else(|| {
                    Error::format(
                        path,
                        format!(
                            "line {line_no}: {} = `{field}` is not a number",
                            ["lambda_nm", "r", "g", "b"][k]
                        ),
                    )
                })?;
            }
            rows.push((row[0], [row[1], row[2], row[3]]));
            lines.push(line_no);
        }
        // `lines` may start with the header's line: keep the data rows' own.
        let data_lines = &lines[lines.len() - rows.len()..];
        Self::resample(
            &rows,
            Origin::File {
                path,
                lines: data_lines,
            },
        )
    }

    /// Curves from samples `(lambda_nm, [r, g, b])` in increasing wavelength, resampled as
    /// [`Sensitivity::from_csv`] does (and validated the same way).
    pub fn from_samples(samples: &[(f64, [f64; 3])]) -> Result<Self> {
        Self::resample(samples, Origin::Samples)
    }

    fn resample(rows: &[(f64, [f64; 3])], origin: Origin) -> Result<Self> {
        for (r, (lambda, rgb)) in rows.iter().enumerate() {
            if !lambda.is_finite() {
                return Err(origin.error(Some(r), format!("wavelength {lambda} is not finite")));
            }
            for c in Channel::ALL {
                let v = rgb[c.index()];
                if !v.is_finite() {
                    return Err(origin.error(Some(r), format!("{} = {v} is not finite", c.name())));
                }
            }
            if r > 0 && *lambda <= rows[r - 1].0 {
                return Err(origin.error(
                    Some(r),
                    format!(
                        "wavelength {lambda} nm does not increase (the row before is at {} nm)",
                        rows[r - 1].0
                    ),
                ));
            }
        }
        if rows.len() < 2 {
            return Err(origin.error(
                None,
                format!(
                    "{} data row(s); a sensitivity needs at least 2 (lambda_nm,r,g,b)",
                    rows.len()
                ),
            ));
        }
        let (first, last) = (rows[0].0, rows[rows.len() - 1].0);
        if last <= GRID_START_NM || first >= GRID_END_NM {
            return Err(origin.error(
                None,
                format!(
                    "the rows cover {first}-{last} nm, outside the visible range \
                     {GRID_START_NM}-{GRID_END_NM} nm"
                ),
            ));
        }
        let mut curves = [
            vec![0.0; GRID_LEN],
            vec![0.0; GRID_LEN],
            vec![0.0; GRID_LEN],
        ];
        for i in 0..GRID_LEN {
            let lambda = grid_wavelength_nm(i);
            if lambda < first || lambda > last {
                continue;
            }
            // The segment [rows[k], rows[k + 1]] holding λ.
            let k = rows
                .partition_point(|row| row.0 <= lambda)
                .clamp(1, rows.len() - 1)
                - 1;
            let (l0, v0) = rows[k];
            let (l1, v1) = rows[k + 1];
            let f = (lambda - l0) / (l1 - l0);
            for (c, curve) in curves.iter_mut().enumerate() {
                curve[i] = v0[c] * (1.0 - f) + v1[c] * f;
            }
        }
        let sensitivity = Sensitivity { curves };
        for c in Channel::ALL {
            let response = sensitivity.response(c, Illuminant::EqualEnergy);
            if response.is_nan() || response <= 0.0 {
                return Err(origin.error(
                    None,
                    format!(
                        "channel {} integrates to {response} over {GRID_START_NM}-{GRID_END_NM} nm; \
                         each channel must respond positively to a flat spectrum",
                        c.name()
                    ),
                ));
            }
        }
        Ok(sensitivity)
    }

    /// q_c on the grid (sample i at [`grid_wavelength_nm`]`(i)`).
    pub fn curve(&self, channel: Channel) -> &[f64] {
        &self.curves[channel.index()]
    }

    /// q_c at `lambda_nm`, linearly interpolated between grid samples; 0 outside 380-780 nm.
    pub fn value(&self, channel: Channel, lambda_nm: f64) -> f64 {
        let x = (lambda_nm - GRID_START_NM) / GRID_STEP_NM;
        if !(0.0..=(GRID_LEN - 1) as f64).contains(&x) {
            return 0.0;
        }
        let i = (x.floor() as usize).min(GRID_LEN - 2);
        let f = x - i as f64;
        let curve = self.curve(channel);
        curve[i] * (1.0 - f) + curve[i + 1] * f
    }

    /// ∫ S(λ)·q_c(λ) dλ over 380-780 nm (Simpson): channel c's raw value for illuminant S
    /// at unit scale.
    pub fn response(&self, channel: Channel, illuminant: Illuminant) -> f64 {
        simpson_weights()
            .iter()
            .zip(self.curve(channel))
            .enumerate()
            .map(|(i, (w, q))| w * q * illuminant.power(grid_wavelength_nm(i)))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn parse(text: &str) -> Result<Sensitivity> {
        Sensitivity::parse_csv(text, &PathBuf::from("cam.csv"))
    }

    #[test]
    fn wyman_fit_peaks_where_the_cie_observer_does() {
        // Tabulated CIE 1931 values: ȳ(555) = 1.0000, x̄(600) = 1.0622, z̄(445) = 1.7826.
        assert!((cie_1931_xyz(555.0)[1] - 1.0).abs() < 0.02);
        assert!((cie_1931_xyz(600.0)[0] - 1.0622).abs() < 0.02);
        assert!((cie_1931_xyz(445.0)[2] - 1.7826).abs() < 0.05);
        // Each function integrates to about 106.86 (the CIE table's sum at 1 nm).
        let w = simpson_weights();
        for k in 0..3 {
            let area: f64 = (0..GRID_LEN)
                .map(|i| w[i] * cie_1931_xyz(grid_wavelength_nm(i))[k])
                .sum();
            assert!((area / 106.86 - 1.0).abs() < 0.02, "{k}: {area}");
        }
    }

    #[test]
    fn d65_is_white_in_the_default_camera() {
        let s = Sensitivity::cie_srgb();
        let rgb = Channel::ALL.map(|c| s.response(c, Illuminant::D65));
        for c in 0..3 {
            assert!((rgb[c] / rgb[1] - 1.0).abs() < 2e-3, "{rgb:?}");
        }
        // The curves are signed: r dips below zero in the blue-green, b in the yellow.
        assert!(s.value(Channel::R, 500.0) < 0.0);
        assert!(s.value(Channel::B, 580.0) < 0.0);
        assert!(s.value(Channel::G, 540.0) > 0.0);
        assert_eq!(Illuminant::D65.power(560.0), 100.0);
        assert!((Illuminant::D65.power(562.0) - (100.0 * 0.6 + 98.1671 * 0.4)).abs() < 1e-12);
    }

    #[test]
    fn csv_is_resampled_linearly_and_zero_outside() {
        let s = parse(
            "# a camera\nlambda_nm, r, g, b\n400,0,1,2  # first\n\n500,1,1,0\n600, 0.5 ,1,0\n",
        )
        .unwrap();
        assert_eq!(s.value(Channel::R, 450.0), 0.5);
        assert_eq!(s.value(Channel::B, 425.0), 1.5);
        assert_eq!(s.value(Channel::R, 550.0), 0.75);
        assert_eq!(s.value(Channel::G, 399.0), 0.0);
        assert_eq!(s.value(Channel::G, 601.0), 0.0);
        assert_eq!(s.value(Channel::G, 600.0), 1.0);
        // Rows beyond the grid only shape the interpolation inside it.
        let wide = parse("300,1,1,1\n900,1,1,1\n").unwrap();
        assert_eq!(wide.curve(Channel::G), &[1.0; GRID_LEN][..]);
        // No header; CRLF; a byte-order mark.
        assert!(parse("380,1,1,1\n780,1,1,1").is_ok());
        let bom = parse("\u{feff}380,1,1,1\r\n780,2,2,2\r\n").unwrap();
        assert_eq!(bom.value(Channel::R, 380.0), 1.0);
    }

    #[test]
    fn bad_csv_names_file_line_and_value() {
        let err = |text: &str| parse(text).unwrap_err().to_string();
        let e = err("lambda_nm,r,g,b\n400,1,1,1\n390,1,1,1\n");
        assert!(
            e.contains("cam.csv") && e.contains("line 3") && e.contains("390"),
            "{e}"
        );
        let e = err("400,1,1,1\n500,1,x,1\n");
        assert!(e.contains("line 2") && e.contains("g = `x`"), "{e}");
        let e = err("400,1,x,1\n500,1,1,1\n");
        assert!(e.contains("line 1") && e.contains("g = `x`"), "{e}");
        let e = err("400,1,1,1\n500,1,NaN,1\n");
        assert!(e.contains("line 2") && e.contains("g = NaN"), "{e}");
        let e = err("400,1,1,1\n500,1,inf,1\n");
        assert!(e.contains("line 2") && e.contains("not finite"), "{e}");
        let e = err("# c\n400,1,1\n");
        assert!(e.contains("line 2") && e.contains("3 fields"), "{e}");
        let e = err("800,1,1,1\n900,1,1,1\n");
        assert!(e.contains("800-900") && e.contains("outside"), "{e}");
        let e = err("header\n500,1,1,1\n");
        assert!(e.contains("at least 2"), "{e}");
        let e = err("header\nanother header\n");
        assert!(e.contains("line 2"), "{e}");
        let e = err("400,1,-1,1\n500,1,-1,1\n");
        assert!(e.contains("channel g"), "{e}");
        let e = Sensitivity::from_csv("no-such-folder/cam.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no-such-folder/cam.csv"), "{e}");
        let e = Sensitivity::from_samples(&[(400.0, [1.0; 3]), (400.0, [1.0; 3])])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("row 1") && e.contains("does not increase"),
            "{e}"
        );
    }
}
