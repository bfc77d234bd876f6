//! The one error type of brume. Every variant says what failed, on which file, shader or
//! extension, and what the user can do about it.
//!
//! A message that tells the caller to set another option names it as a field in
//! backticks (`` `depth_scale` ``), never as one host's spelling of it: each host shows
//! them as its own ([`Error::rename_options`], [`rename_options`]), the command line as
//! its flags (`--depth-scale`), the Python package as its keywords.

use std::path::PathBuf;

/// Result alias used across brume.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in brume, typed so that callers can react and the CLI can
/// print one clear line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// A file was read but its content is not what its format requires.
    #[error("{}: {detail}", path.display())]
    Format {
        /// The offending file.
        path: PathBuf,
        /// What was found and what was expected.
        detail: String,
    },
    /// A parameter given by the user (or a library caller) is out of its domain.
    #[error("invalid {name} = {value}: expected {expected}")]
    InvalidParameter {
        /// The option or field name, e.g. `--ks`.
        name: String,
        /// The value given, as text.
        value: String,
        /// What would have been accepted.
        expected: String,
    },
    /// Two inputs that must have the same size do not.
    #[error("size mismatch: {a} is {aw}x{ah} but {b} is {bw}x{bh}; both must have the same size")]
    SizeMismatch {
        /// First input.
        a: String,
        /// Its width.
        aw: u32,
        /// Its height.
        ah: u32,
        /// Second input.
        b: String,
        /// Its width.
        bw: u32,
        /// Its height.
        bh: u32,
    },
    /// A range or depth map holds no usable value at all.
    #[error("{}: no valid depth value (every pixel unknown: NaN, infinite, zero or negative)", path.display())]
    NoValidDepth {
        /// The depth file.
        path: PathBuf,
    },
    /// EGL could not be loaded or no display/context could be created.
    #[error("EGL: {0}")]
    Egl(String),
    /// A GL capability that brume needs is missing on this driver.
    #[error("the GL driver ({renderer}) lacks {capability}: {hint}")]
    MissingCapability {
        /// The extension or limit, e.g. `GL_EXT_color_buffer_float`.
        capability: String,
        /// GL_RENDERER of the driver.
        renderer: String,
        /// What to do instead.
        hint: String,
    },
    /// A shader failed to compile or a program failed to link.
    #[error("shader {name} failed to {stage}:\n{log}")]
    Shader {
        /// Shader file name, e.g. `diffuse.frag`.
        name: String,
        /// `compile` or `link`.
        stage: &'static str,
        /// The driver's info log.
        log: String,
    },
    /// Any other GL failure (object creation, incomplete framebuffer, glGetError).
    #[error("GL: {0}")]
    Gl(String),
    /// An image is larger than the driver can hold in one texture.
    #[error("{what} is {width}x{height} but GL_MAX_TEXTURE_SIZE of {renderer} is {max}: downscale the input")]
    TooLarge {
        /// Which input.
        what: String,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// The driver limit.
        max: u32,
        /// GL_RENDERER.
        renderer: String,
    },
    /// Memory ran out, or would: the GL driver's `GL_OUT_OF_MEMORY`, or a render that
    /// cannot fit in what the machine has left, refused before allocating.
    #[error("out of memory: {what} {detail}; {hint}")]
    OutOfMemory {
        /// What needed the memory, e.g. `a 8000x6000 render`.
        what: String,
        /// How much was needed and how much there was, where known.
        detail: String,
        /// What to do instead.
        hint: String,
    },
    /// A window could not be opened or drawn to (`brume view`).
    #[error("window: {what}: {detail}; {hint}")]
    Window {
        /// The step that failed.
        what: String,
        /// What the windowing or GL library said.
        detail: String,
        /// What to do about it.
        hint: String,
    },
    /// Some frames of a batch failed; the others were written.
    #[error("{frames} frames and {outputs} outputs failed ({written} outputs written); each failure is in {}", log.display())]
    BatchFailures {
        /// Frames that could not be loaded or rendered.
        frames: usize,
        /// Outputs that could not be written.
        outputs: usize,
        /// Outputs written by the run.
        written: usize,
        /// The run's log.
        log: PathBuf,
    },
    /// Range pre-processing (hole filling, sky, horizon margin) cannot proceed.
    #[error("pre-processing: {0}")]
    Prep(String),
    /// A medium that reads a depth buffer was given a frame without its camera.
    #[error(
        "the {medium} medium reads a depth buffer and needs the frame's camera: pass \
         FrameInputs {{ camera: Some(..), .. }} (brume's Camera or the engine's MatrixCamera) \
         with the frame"
    )]
    MissingCamera {
        /// The medium's name.
        medium: String,
    },
}

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    /// A format error on `path` with a message saying what was found and expected.
    pub fn format(path: impl Into<PathBuf>, detail: impl Into<String>) -> Self {
        Error::Format {
            path: path.into(),
            detail: detail.into(),
        }
    }

    /// [`Error::SizeMismatch`]: input `a` is `a_size` (width, height) where `b` is
    /// `b_size`.
    pub fn size_mismatch(
        a: impl std::fmt::Display,
        a_size: (usize, usize),
        b: impl std::fmt::Display,
        b_size: (usize, usize),
    ) -> Self {
        Error::SizeMismatch {
            a: a.to_string(),
            aw: a_size.0 as u32,
            ah: a_size.1 as u32,
            b: b.to_string(),
            bw: b_size.0 as u32,
            bh: b_size.1 as u32,
        }
    }

    /// An out-of-domain parameter.
    pub fn invalid(
        name: impl Into<String>,
        value: impl std::fmt::Display,
        expected: impl Into<String>,
    ) -> Self {
        Error::InvalidParameter {
            name: name.into(),
            value: compact_number(value.to_string()),
            expected: expected.into(),
        }
    }

    /// This error with the options it names shown as a host calls them: the parameter's
    /// name, and every option a message names in backticks, become what `rename` gives
    /// for the field (kept as they are where it gives `None`).
    pub fn rename_options(self, rename: impl Fn(&str) -> Option<String>) -> Error {
        let text = |t: String| rename_options(&t, &rename);
        match self {
            Error::InvalidParameter {
                name,
                value,
                expected,
            } => Error::InvalidParameter {
                name: rename(&name).unwrap_or(name),
                value,
                expected: text(expected),
            },
            Error::Format { path, detail } => Error::Format {
                path,
                detail: text(detail),
            },
            Error::Prep(detail) => Error::Prep(text(detail)),
            Error::OutOfMemory { what, detail, hint } => Error::OutOfMemory {
                what: text(what),
                detail,
                hint: text(hint),
            },
            other => other,
        }
    }
}

/// `text` with every option it names in backticks (`` `depth_scale` ``) replaced, the
/// backticks included, by what `rename` gives for the field; kept where it gives `None`.
pub fn rename_options(text: &str, rename: impl Fn(&str) -> Option<String>) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(open) = rest.find('`') {
        let (before, quoted) = rest.split_at(open);
        out.push_str(before);
        let field = quoted[1..].find('`').map(|close| &quoted[1..1 + close]);
        match field
            .filter(|f| is_field_name(f))
            .and_then(|f| Some((f, rename(f)?)))
        {
            Some((field, shown)) => {
                out.push_str(&shown);
                rest = &quoted[field.len() + 2..];
            }
            None => {
                out.push('`');
                rest = &quoted[1..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// Whether `text` can be a field's name: lower-case letters, digits and underscores.
fn is_field_name(text: &str) -> bool {
    !text.is_empty()
        && text
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_')
}

/// Accepts a finite `value` > 0, or names the parameter.
pub fn check_positive(name: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(name, value, "a finite number > 0"))
    }
}

/// Accepts a finite `value` ≥ 0, or names the parameter.
pub fn check_non_negative(name: &str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(name, value, "a finite number ≥ 0"))
    }
}

/// A decimal that scientific notation says much shorter (`1e308` prints as 309 digits,
/// `1e-9` as `0.000000001`) in scientific notation; anything else as it is.
fn compact_number(text: String) -> String {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => {
            let scientific = format!("{v:e}");
            if scientific.len() + 3 <= text.len() {
                scientific
            } else {
                text
            }
        }
        _ => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_are_shown_compactly() {
        let shown = |v: f64| Error::invalid("x", v, "y").to_string();
        assert_eq!(shown(1e308), "invalid x = 1e308: expected y");
        assert_eq!(shown(1e-9), "invalid x = 1e-9: expected y");
        assert_eq!(shown(0.25), "invalid x = 0.25: expected y");
        assert_eq!(shown(207043.0), "invalid x = 207043: expected y");
        assert_eq!(shown(f64::INFINITY), "invalid x = inf: expected y");
    }

    #[test]
    fn options_in_backticks_are_renamed_and_other_text_kept() {
        let flag = |f: &str| (f != "unknown").then(|| format!("--{}", f.replace('_', "-")));
        assert_eq!(
            rename_options(
                "`depth_scale` ignored; see `unknown`, a `Code block`, `",
                flag
            ),
            "--depth-scale ignored; see `unknown`, a `Code block`, `"
        );
        assert_eq!(rename_options("``", flag), "``");
        let e = Error::invalid("sigma0", 0, "more, or set `blur_kind`").rename_options(flag);
        assert_eq!(
            e.to_string(),
            "invalid --sigma0 = 0: expected more, or set --blur-kind"
        );
        let e = Error::format("a.png", "give `camera`").rename_options(flag);
        assert_eq!(e.to_string(), "a.png: give --camera");
    }
}
