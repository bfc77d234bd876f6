//! The pipeline's programs: which passes exist ([`ProgramKey`]), how each is assembled
//! from the prelude, the medium's GLSL and the pass, and the cache that compiles each once.

use super::engine::{self, EngineKey};
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
/// per grey or chromatic τ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum ProgramKey {
    Medium {
        medium: MediumId,
        chromatic: bool,
        log_rate: bool,
        half_rate: bool,
    },
    Diffuse {
        matched: bool,
        chromatic: bool,
    },
    Composite {
        medium: MediumId,
        chromatic: bool,
        /// Also the coarse stage's last blend (`coarse_detail.glsl`).
        coarse: bool,
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
    chromatic: bool,
) -> ProgramKey {
    ProgramKey::Medium {
        medium: MediumId::of(medium),
        chromatic,
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
        let defines = |pairs: &[(&str, bool)]| {
            let mut header = self.version_line.to_string();
            for (name, on) in pairs {
                header.push_str(&format!("\n#define {name} {}", i32::from(*on)));
            }
            header.push('\n');
            header.push_str(PRELUDE_GLSL);
            header
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
                chromatic,
                log_rate,
                half_rate,
                ..
            } => Program::new(
                &self.gl,
                &defines(&[
                    ("CHROMATIC", chromatic),
                    ("RATE_LAW_LOG", log_rate),
                    ("RATE_HALF", half_rate),
                ]),
                (&names("medium.frag"), &with_medium(MEDIUM_FRAG)),
                &["u_colour"],
                &as_strs(&optional(&["u_depth", "u_colour_srgb", "u_schedule"])),
            ),
            ProgramKey::Diffuse { matched, chromatic } => Program::new(
                &self.gl,
                &defines(&[("VARIANCE_MATCHED", matched), ("CHROMATIC", chromatic)]),
                ("diffuse.frag", DIFFUSE_FRAG),
                &["u_f", "u_rate", "u_law", "u_texel"],
                &["u_tau_gb"],
            ),
            ProgramKey::Composite {
                chromatic, coarse, ..
            } => Program::new(
                &self.gl,
                &defines(&[("CHROMATIC", chromatic), ("COARSE_BLEND", coarse)]),
                (
                    &names("composite.frag"),
                    &with_medium(&composite_source(coarse)),
                ),
                if coarse {
                    &BLEND_UNIFORMS
                } else {
                    &BLEND_UNIFORMS[..1]
                },
                &as_strs(&optional(&[
                    "u_depth",
                    "u_tau_gb",
                    "u_origin",
                    "u_output_srgb",
                ])),
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

/// The coarse stage's blend's uniforms (`coarse_blend.frag`, and the composite with
/// `COARSE_BLEND`); `u_f` alone is the plain composite's.
pub(super) const BLEND_UNIFORMS: [&str; 6] = [
    "u_f",
    "u_rate",
    "u_coarse",
    "u_coarse0",
    "u_half_texel",
    "u_detail",
];

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
