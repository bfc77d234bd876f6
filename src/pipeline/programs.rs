//! The pipeline's programs: which passes exist ([`ProgramKey`]), how each is assembled
//! from the prelude, the medium's GLSL and the pass, and the cache that compiles each once.

use super::engine::{self, EngineKey};
use super::targets::Layout;
use super::{external, refine, Pipeline};
use crate::blur::Precision;
use crate::camera::FrameInputs;
use crate::error::{Error, Result};
use crate::gpu::program::Program;
use crate::medium::{Medium, MEDIUM_API_GLSL};
use crate::schedule::{Schedule, Scheme};
use std::borrow::Cow;
use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

pub(super) const PRELUDE_GLSL: &str = include_str!("../../glsl/prelude.glsl");
pub(super) const MEDIUM_FRAG: &str = include_str!("../../glsl/medium.frag");
pub(super) const DIFFUSE_FRAG: &str = include_str!("../../glsl/diffuse.frag");
pub(super) const COMPOSITE_FRAG: &str = include_str!("../../glsl/composite.frag");
pub(super) const COARSE_DETAIL_GLSL: &str = include_str!("../../glsl/coarse_detail.glsl");
const COARSE_DOWN_FRAG: &str = include_str!("../../glsl/coarse_down.frag");
const COARSE_BLEND_FRAG: &str = include_str!("../../glsl/coarse_blend.frag");

/// A medium's GLSL identity: a 128-bit hash of its source text. The program cache is
/// keyed by it, not by [`Medium::name`], so two media of one name with different GLSL
/// (one defined at run time, say) never share a program, and one medium whose GLSL is
/// rebuilt identically keeps its program.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) struct MediumId(u64, u64);

impl MediumId {
    /// The identity of `medium`'s GLSL.
    pub(super) fn of(medium: &dyn Medium) -> Self {
        let glsl = medium.glsl();
        let hash = |seed: u64| {
            let mut h = DefaultHasher::new();
            seed.hash(&mut h);
            glsl.hash(&mut h);
            h.finish()
        };
        MediumId(hash(0), hash(1))
    }
}

/// Which program: the medium's two passes are compiled per medium GLSL, and every pass
/// of the diffusion per layout of its targets ([`Layout`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum ProgramKey {
    Medium {
        medium: MediumId,
        layout: Layout,
        log_rate: bool,
        half_rate: bool,
    },
    Diffuse {
        matched: bool,
        layout: Layout,
    },
    Composite {
        medium: MediumId,
        layout: Layout,
        /// Also the coarse stage's last blend (`coarse_detail.glsl`).
        coarse: bool,
    },
    /// The coarse stage's 2x2 average (`coarse.rs`), ρ in alpha or not.
    CoarseDown {
        rate_in_alpha: bool,
    },
    /// The coarse stage's blend of a level into the next finer one.
    CoarseBlend {
        rate_in_alpha: bool,
    },
    /// An engine pass (see [`engine`]) of a medium.
    Engine(MediumId, EngineKey),
    /// The import of an external image (see [`external`]).
    ExternalImport,
    /// A pass of the image-guided refinement (see [`refine`]).
    Refine(refine::RefinePass),
}

/// The medium pass's program for this frame.
pub(super) fn medium_key(
    medium: &dyn Medium,
    precision: Precision,
    schedule: &Schedule,
    layout: Layout,
) -> ProgramKey {
    ProgramKey::Medium {
        medium: MediumId::of(medium),
        layout,
        log_rate: schedule.scheme != Scheme::Euler,
        half_rate: precision == Precision::F16,
    }
}

impl Pipeline {
    pub(super) fn compiled(&self, key: ProgramKey) -> Result<&Program> {
        self.programs
            .get(&key)
            .ok_or_else(|| Error::Gl(format!("internal: program {key:?} not compiled")))
    }

    /// The program for `key`, compiled on first use (`medium` is needed for the medium
    /// and composite passes).
    pub(super) fn program(
        &mut self,
        key: ProgramKey,
        medium: Option<&dyn Medium>,
    ) -> Result<&Program> {
        if !self.programs.contains_key(&key) {
            let program = self.compile(key, medium)?;
            self.programs.insert(key, program);
        }
        self.compiled(key)
    }

    pub(super) fn compile(&self, key: ProgramKey, medium: Option<&dyn Medium>) -> Result<Program> {
        // The rate's own texture, read by every diffusion pass but in the offset layout.
        let rate = |rate_in_alpha: bool| if rate_in_alpha { None } else { Some("u_rate") };
        let defines = |pairs: &[(&str, bool)]| {
            let mut header = self.version_line.to_string();
            for (name, on) in pairs {
                header.push_str(&format!("\n#define {name} {}", i32::from(*on)));
            }
            header.push('\n');
            header.push_str(PRELUDE_GLSL);
            header
        };
        let layout_defines = |layout: Layout, more: &[(&str, bool)]| {
            let mut pairs = vec![
                ("CHROMATIC", layout.tau_pair()),
                ("OFFSET_LAYOUT", layout.rate_in_alpha()),
            ];
            pairs.extend_from_slice(more);
            defines(&pairs)
        };
        let with_medium = |pass: &str| {
            let m = medium.expect("the medium passes need a medium");
            format!("{MEDIUM_API_GLSL}\n{}\n{pass}", m.glsl())
        };
        let names = |pass: &str| {
            let m = medium.expect("the medium passes need a medium");
            format!("{pass} with glsl/medium/{}.glsl", m.name())
        };
        let optional = |extra: &[&'static str]| {
            let mut list: Vec<Cow<'static, str>> = MEDIUM_API_UNIFORMS
                .iter()
                .map(|&n| Cow::Borrowed(n))
                .collect();
            list.extend(extra.iter().map(|&n| Cow::Borrowed(n)));
            if let Some(m) = medium {
                // The names do not depend on the frame (Medium::uniforms).
                let names = m.uniforms(&FrameInputs::default());
                list.extend(names.into_iter().map(|(name, _)| name));
                list.extend(m.lookups().into_iter().map(|(name, _)| name));
            }
            list
        };
        match key {
            ProgramKey::Medium {
                layout,
                log_rate,
                half_rate,
                ..
            } => Program::new(
                &self.gl,
                &layout_defines(
                    layout,
                    &[("RATE_LAW_LOG", log_rate), ("RATE_HALF", half_rate)],
                ),
                (&names("medium.frag"), &with_medium(MEDIUM_FRAG)),
                &["u_colour"],
                &as_strs(&optional(&["u_depth", "u_colour_srgb", "u_schedule"])),
            ),
            ProgramKey::Diffuse { matched, layout } => Program::new(
                &self.gl,
                &layout_defines(layout, &[("VARIANCE_MATCHED", matched)]),
                ("diffuse.frag", DIFFUSE_FRAG),
                &with_rate(&["u_f", "u_law", "u_texel"], rate(layout.rate_in_alpha())),
                &["u_tau_gb"],
            ),
            ProgramKey::Composite { layout, coarse, .. } => Program::new(
                &self.gl,
                &layout_defines(layout, &[("COARSE_BLEND", coarse)]),
                (
                    &names("composite.frag"),
                    &with_medium(&composite_source(coarse)),
                ),
                &if coarse {
                    with_rate(&BLEND_UNIFORMS, rate(layout.rate_in_alpha()))
                } else {
                    vec!["u_f"]
                },
                &as_strs(&optional(&[
                    "u_depth",
                    "u_tau_gb",
                    "u_origin",
                    "u_output_srgb",
                ])),
            ),
            ProgramKey::CoarseDown { rate_in_alpha } => Program::new(
                &self.gl,
                &defines(&[("OFFSET_LAYOUT", rate_in_alpha)]),
                ("coarse_down.frag", COARSE_DOWN_FRAG),
                &with_rate(&["u_f", "u_texel"], rate(rate_in_alpha)),
                &[],
            ),
            ProgramKey::CoarseBlend { rate_in_alpha } => Program::new(
                &self.gl,
                &defines(&[("OFFSET_LAYOUT", rate_in_alpha)]),
                (
                    "coarse_blend.frag",
                    &format!("{COARSE_DETAIL_GLSL}\n{COARSE_BLEND_FRAG}"),
                ),
                &with_rate(&BLEND_UNIFORMS, rate(rate_in_alpha)),
                &[],
            ),
            ProgramKey::Engine(_, key) => {
                let (file, source, pairs) = key.source();
                let gauss = if key.needs_gauss() {
                    engine::GAUSS5
                } else {
                    ""
                };
                Program::new(
                    &self.gl,
                    &defines(&pairs),
                    (&names(file), &with_medium(&format!("{gauss}\n{source}"))),
                    &[],
                    &as_strs(&optional(&engine::ENGINE_UNIFORMS)),
                )
            }
            ProgramKey::ExternalImport => external::compile(&self.gl, self.version_line),
            ProgramKey::Refine(pass) => {
                refine::compile(&self.gl, self.version_line, PRELUDE_GLSL, pass)
            }
        }
    }

    /// A medium uniform that neither of its passes uses is misspelled (or dead): say so
    /// instead of rendering with a default value.
    pub(super) fn check_medium_uniforms(
        &self,
        medium: &dyn Medium,
        first: ProgramKey,
        last: ProgramKey,
    ) -> Result<()> {
        let (first, last) = (self.compiled(first)?, self.compiled(last)?);
        for (name, _) in medium.uniforms(&FrameInputs::default()) {
            if first.optional_uniform(&name).is_none() && last.optional_uniform(&name).is_none() {
                return Err(Error::Gl(format!(
                    "glsl/medium/{}.glsl: uniform {name} is not used by the shader \
                     (misspelled, or not declared)",
                    medium.name()
                )));
            }
        }
        Ok(())
    }
}

/// Borrowed names, as [`Program::new`] takes them.
/// The composite pass's source: with the coarse stage's blend in front of it, or alone.
fn composite_source(coarse: bool) -> Cow<'static, str> {
    if coarse {
        Cow::Owned(format!("{COARSE_DETAIL_GLSL}\n{COMPOSITE_FRAG}"))
    } else {
        Cow::Borrowed(COMPOSITE_FRAG)
    }
}

/// `names` and the rate's own texture where the pass reads one.
fn with_rate<'a>(names: &[&'a str], rate: Option<&'a str>) -> Vec<&'a str> {
    names.iter().copied().chain(rate).collect()
}

/// The coarse stage's blend's uniforms (`coarse_blend.frag`, and the composite with
/// `COARSE_BLEND`) but the rate's texture, which the offset layout does not have.
const BLEND_UNIFORMS: [&str; 5] = ["u_f", "u_coarse", "u_coarse0", "u_half_texel", "u_detail"];

fn as_strs<'a>(names: &'a [Cow<'static, str>]) -> Vec<&'a str> {
    names.iter().map(|n| n.as_ref()).collect()
}

/// The uniforms of `glsl/medium_api.glsl` and `glsl/fullscreen.vert` that the pipeline
/// sets for every medium pass (unused ones are optimised out).
const MEDIUM_API_UNIFORMS: [&str; 5] = [
    "brume_sigma0",
    "brume_size",
    "brume_corner_rays",
    "brume_depth_constants",
    "brume_eye",
];
