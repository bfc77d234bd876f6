//! Every fact about a depth format in one table, [`DepthFormat::rule`]: its name, the file
//! layout it expects, the kind of values it holds, and a 16-bit dataset's fixed scale. A
//! new dataset convention adds its [`DepthFormat`] variant and its row here; only a
//! conversion no row can describe (a calibration file, a stereo geometry) also adds a
//! module beside `middlebury.rs` and its arm in `interpret`.

use super::raw::Raw;
use super::{DepthFormat, DepthKind};

/// The layout of the file a format reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Layout {
    /// Decided from the file (`auto`).
    Any,
    /// A `Pf` PFM (Middlebury 2014 `disp0.pfm`).
    Pfm,
    /// An 8-bit grey PNG.
    Grey8,
    /// A 16-bit grey PNG, or a uint16 `.npy`/`.npz` array.
    Grey16,
    /// Any float map: PFM, EXR, float TIFF, `.npy`, `.npz`.
    Float,
    /// A JPEG with a GDepth depth map in its XMP.
    GDepth,
    /// A JPEG with a Dynamic Depth container.
    DynamicDepth,
    /// A JPEG whose Multi-Picture index lists an image of Apple's depth.
    AppleDepth,
}

impl Layout {
    /// Whether a decoded file has this layout.
    pub(super) fn fits(self, raw: &Raw) -> bool {
        match self {
            Layout::Any => true,
            Layout::Pfm => matches!(raw, Raw::Float { from_pfm: true, .. }),
            Layout::Grey8 => matches!(raw, Raw::Grey8(_)),
            Layout::Grey16 => matches!(raw, Raw::Grey16(_)),
            Layout::Float => matches!(raw, Raw::Float { .. }),
            Layout::GDepth => matches!(raw, Raw::Embedded(e) if e.format == DepthFormat::Gdepth),
            Layout::DynamicDepth => {
                matches!(raw, Raw::Embedded(e) if e.format == DepthFormat::DynamicDepth)
            }
            Layout::AppleDepth => {
                matches!(raw, Raw::Embedded(e) if e.format == DepthFormat::AppleDepth)
            }
        }
    }

    /// What a file of this layout is, for messages.
    pub(super) fn expected(self) -> &'static str {
        match self {
            Layout::Any => "a depth file",
            Layout::Pfm => "a `Pf` PFM disparity (disp0.pfm)",
            Layout::Grey8 => "an 8-bit grey PNG disparity",
            Layout::Grey16 => "a 16-bit grey PNG (or a 16-bit TIFF or uint16 .npy)",
            Layout::Float => "a float map (.pfm, .exr, .tif, .tiff, .npy or .npz)",
            Layout::GDepth => "a JPEG with a GDepth depth map",
            Layout::DynamicDepth => "a JPEG with a Dynamic Depth container",
            Layout::AppleDepth => "an iPhone's portrait JPEG with its depth image",
        }
    }
}

/// Which kinds of values a format may hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kinds {
    /// Depth, range, disparity, a z-buffer or inverse depth (`DepthOptions::kind` says).
    Any,
    /// Disparity only (the Middlebury sets).
    Disparity,
    /// Depth or range, never disparity or a z-buffer (the RGB-D sets).
    DepthOrRange,
}

/// One row of the format table.
#[derive(Clone, Copy, Debug)]
pub(super) struct FormatRule {
    /// The name on the command line and in reports.
    pub name: &'static str,
    /// The file it reads.
    pub layout: Layout,
    /// The kind of values when `DepthOptions::kind` is `None`.
    pub default_kind: DepthKind,
    /// The kinds it accepts.
    pub kinds: Kinds,
    /// Metres per unit of a 16-bit PNG, where the dataset fixes it.
    pub fixed_scale: Option<f64>,
}

impl FormatRule {
    /// Whether values of `kind` can be read in this format.
    pub(super) fn accepts(&self, kind: DepthKind) -> bool {
        match self.kinds {
            Kinds::Any => true,
            Kinds::Disparity => kind == DepthKind::Disparity,
            Kinds::DepthOrRange => matches!(kind, DepthKind::Depth | DepthKind::Range),
        }
    }
}

impl DepthFormat {
    /// Every format, in the order `--help` and errors list them.
    pub const ALL: [DepthFormat; 14] = [
        DepthFormat::Auto,
        DepthFormat::Middlebury2014,
        DepthFormat::Middlebury2006,
        DepthFormat::Kitti,
        DepthFormat::Nyu,
        DepthFormat::Tum,
        DepthFormat::Png16,
        DepthFormat::Float,
        DepthFormat::AndroidDepth16,
        DepthFormat::Arcore,
        DepthFormat::Cityscapes,
        DepthFormat::Gdepth,
        DepthFormat::DynamicDepth,
        DepthFormat::AppleDepth,
    ];

    /// What brume knows of this format (the module docs).
    pub(super) fn rule(self) -> FormatRule {
        use DepthKind::{Depth, Disparity, Range};
        let row = |name, layout, default_kind, kinds, fixed_scale| FormatRule {
            name,
            layout,
            default_kind,
            kinds,
            fixed_scale,
        };
        match self {
            DepthFormat::Auto => row("auto", Layout::Any, Depth, Kinds::Any, None),
            DepthFormat::Middlebury2014 => row(
                "middlebury2014",
                Layout::Pfm,
                Disparity,
                Kinds::Disparity,
                None,
            ),
            DepthFormat::Middlebury2006 => row(
                "middlebury2006",
                Layout::Grey8,
                Disparity,
                Kinds::Disparity,
                None,
            ),
            DepthFormat::Kitti => row(
                "kitti",
                Layout::Grey16,
                Depth,
                Kinds::DepthOrRange,
                Some(1.0 / 256.0),
            ),
            DepthFormat::Nyu => row(
                "nyu",
                Layout::Grey16,
                Depth,
                Kinds::DepthOrRange,
                Some(1.0 / 1000.0),
            ),
            DepthFormat::Tum => row(
                "tum",
                Layout::Grey16,
                Depth,
                Kinds::DepthOrRange,
                Some(1.0 / 5000.0),
            ),
            DepthFormat::Png16 => row("png16", Layout::Grey16, Depth, Kinds::Any, None),
            DepthFormat::Float => row("float", Layout::Float, Depth, Kinds::Any, None),
            // The samples also carry a confidence: the `android` module unpacks them.
            DepthFormat::AndroidDepth16 => row(
                "android-depth16",
                Layout::Grey16,
                Range,
                Kinds::DepthOrRange,
                Some(1.0 / 1000.0),
            ),
            DepthFormat::Arcore => row(
                "arcore",
                Layout::Grey16,
                Depth,
                Kinds::DepthOrRange,
                Some(1.0 / 1000.0),
            ),
            // Disparity (p − 1)/256 px with a camera file: the `cityscapes` module.
            DepthFormat::Cityscapes => row(
                "cityscapes",
                Layout::Grey16,
                Disparity,
                Kinds::Disparity,
                None,
            ),
            // Scaled by its own Near, Far and Units; its MeasureType says depth or range:
            // the `gdepth` module.
            DepthFormat::Gdepth => row("gdepth", Layout::GDepth, Depth, Kinds::DepthOrRange, None),
            DepthFormat::DynamicDepth => row(
                "dynamic-depth",
                Layout::DynamicDepth,
                Depth,
                Kinds::DepthOrRange,
                None,
            ),
            // Disparity or depth as its NativeFormat says, made depth: the `apple` module.
            DepthFormat::AppleDepth => row(
                "apple-depth",
                Layout::AppleDepth,
                Depth,
                Kinds::DepthOrRange,
                None,
            ),
        }
    }

    /// `one of auto, middlebury2014, …`, for messages.
    pub(super) fn names() -> String {
        let names: Vec<&str> = DepthFormat::ALL.iter().map(|f| f.rule().name).collect();
        format!("one of {}", names.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_are_unique() {
        for f in DepthFormat::ALL {
            assert_eq!(f.rule().name.parse::<DepthFormat>().unwrap(), f);
            assert_eq!(f.to_string(), f.rule().name);
        }
        let mut names: Vec<_> = DepthFormat::ALL.iter().map(|f| f.rule().name).collect();
        names.dedup();
        assert_eq!(names.len(), DepthFormat::ALL.len());
    }

    #[test]
    fn the_fixed_scales_are_the_datasets() {
        let scale = |f: DepthFormat| f.rule().fixed_scale.unwrap();
        assert_eq!(scale(DepthFormat::Kitti), 1.0 / 256.0);
        assert_eq!(scale(DepthFormat::Nyu), 1e-3);
        assert_eq!(scale(DepthFormat::Tum), 1.0 / 5000.0);
        assert_eq!(scale(DepthFormat::AndroidDepth16), 1e-3);
        assert_eq!(scale(DepthFormat::Arcore), 1e-3);
        assert!(DepthFormat::Png16.rule().fixed_scale.is_none());
    }
}
