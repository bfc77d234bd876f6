//! The N + 2 passes of a render (module docs of the parent): the medium pass, the
//! diffusion steps and the composite.

use super::coarse::Level;
use super::programs::{medium_key, ProgramKey};
use super::targets::Layout;
use super::uniforms::{bind_texture, set_int, set_value};
use super::{
    draw_fullscreen, Destination, Encoding, Input, Pipeline, UNIT_BLEND_RATE, UNIT_BLEND_START,
    UNIT_DEPTH, UNIT_MAIN, UNIT_SECOND,
};
use crate::error::{Error, Result};
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::program::Program;
use crate::gpu::texture::Texture;
use crate::gpu::timer::PassTimer;
use crate::medium::{Medium, UniformValue};
use crate::schedule::{level_detail_decay, Schedule};

impl Pipeline {
    /// The N + 2 passes (N + 1 + 2L with the coarse stage's L levels: a down and a blend
    /// pass each, the half-resolution level's blend fused with the composite), timed
    /// by `timer`; returns the ping-pong target that is free for an internal result.
    pub(super) fn run_passes(
        &self,
        input: &Input,
        medium: &dyn Medium,
        schedule: &Schedule,
        destination: &Destination,
        timer: &mut PassTimer,
    ) -> Result<usize> {
        let gl = &self.gl;
        let targets = self.targets()?;
        let layout = targets.layout;

        let p = self.compiled(medium_key(medium, targets.precision, schedule, layout))?;
        timer.pass(|| {
            targets.first.bind_for_drawing();
            self.use_program(p);
            bind_texture(gl, UNIT_MAIN, Some(input.colour));
            bind_texture(gl, UNIT_DEPTH, Some(input.depth));
            set_int(gl, p, "u_colour", UNIT_MAIN as i32);
            set_int(gl, p, "u_depth", UNIT_DEPTH as i32);
            set_int(
                gl,
                p,
                "u_colour_srgb",
                i32::from(input.colour_encoding == Encoding::Srgb),
            );
            let inverse_steps = if schedule.steps == 0 {
                0.0
            } else {
                1.0 / f64::from(schedule.steps)
            };
            set_value(
                gl,
                p,
                "u_schedule",
                UniformValue::Vec2([schedule.sigma_max as f32, inverse_steps as f32]),
            );
            self.set_medium_uniforms(p, medium, input, schedule.sigma0);
            draw_fullscreen(gl);
        })?;

        let law = schedule.offset_law();
        let d = self.compiled(ProgramKey::Diffuse {
            matched: law.matched,
            layout,
        })?;
        let texel = [1.0 / input.width as f32, 1.0 / input.height as f32];
        let full_steps = self.coarse_start.unwrap_or(schedule.steps);
        let mut current = 0;
        for k in 0..full_steps {
            let (src, dst) = (current, 1 - current);
            timer.pass(|| {
                targets.step[dst].bind_for_drawing();
                self.use_program(d);
                targets.f[src].bind(UNIT_MAIN);
                if let Some(rate) = &targets.rate {
                    rate.bind(UNIT_DEPTH);
                }
                if let Some(pair) = &targets.tau_gb {
                    pair[src].bind(UNIT_SECOND);
                }
                set_int(gl, d, "u_f", UNIT_MAIN as i32);
                set_int(gl, d, "u_rate", UNIT_DEPTH as i32);
                set_int(gl, d, "u_tau_gb", UNIT_SECOND as i32);
                set_value(gl, d, "u_law", UniformValue::Vec2(law.uniform(k)));
                set_value(gl, d, "u_texel", UniformValue::Vec2(texel));
                draw_fullscreen(gl);
            })?;
            current = dst;
        }
        // With the coarse stage, `current` keeps F at its first step, and the composite
        // is also the half-resolution level's blend into full resolution.
        let coarse = match self.coarse_start {
            Some(start) => Some(self.run_coarse(schedule, start, current, timer)?),
            None => None,
        };

        let c = self.compiled(ProgramKey::Composite {
            medium: super::programs::MediumId::of(medium),
            layout,
            coarse: coarse.is_some(),
        })?;
        let free = 1 - current;
        timer.pass(|| {
            let (origin, encoding) =
                self.bind_destination(destination, input, Some(&targets.step[free]));
            self.use_program(c);
            match &coarse {
                Some(last) => self.bind_blend(c, last, schedule),
                None => {
                    targets.f[current].bind(UNIT_MAIN);
                    set_int(gl, c, "u_f", UNIT_MAIN as i32);
                }
            }
            bind_texture(gl, UNIT_DEPTH, Some(input.depth));
            if let Some(pair) = &targets.tau_gb {
                pair[current].bind(UNIT_SECOND);
            }
            set_int(gl, c, "u_depth", UNIT_DEPTH as i32);
            set_int(gl, c, "u_tau_gb", UNIT_SECOND as i32);
            set_value(gl, c, "u_origin", UniformValue::IVec2(origin));
            set_int(
                gl,
                c,
                "u_output_srgb",
                i32::from(encoding == Encoding::Srgb),
            );
            self.set_medium_uniforms(c, medium, input, schedule.sigma0);
            draw_fullscreen(gl);
        })?;
        Ok(free)
    }

    /// The coarse stage (`coarse.rs`) from step `start`, full-resolution F at `start` in
    /// target `current`: for each level, down from the finer one and its steps; then the
    /// blends between coarse levels, deepest first. Returns what the composite reads to
    /// blend the half-resolution level into full resolution.
    fn run_coarse<'a>(
        &'a self,
        schedule: &Schedule,
        start: u32,
        current: usize,
        timer: &mut PassTimer,
    ) -> Result<BlendInputs<'a>> {
        let targets = self.targets()?;
        let starts = &self.coarse.starts;
        let levels = match &self.coarse.targets {
            Some(t) if starts.first() == Some(&start) && t.levels.len() >= starts.len() => {
                &t.levels[..starts.len()]
            }
            _ => return Err(Error::Gl("internal: coarse stage not prepared".into())),
        };
        let rate_in_alpha = targets.layout.rate_in_alpha();
        let down = self.compiled(ProgramKey::CoarseDown { rate_in_alpha })?;
        let blend = self.compiled(ProgramKey::CoarseBlend { rate_in_alpha })?;
        let full_texel = [1.0 / targets.width as f32, 1.0 / targets.height as f32];
        // Which of each level's D targets holds its latest result.
        let mut latest = vec![0usize; levels.len()];
        for (l, level) in levels.iter().enumerate() {
            let (source, rate, texel) = match l {
                0 => (&targets.f[current], targets.rate.as_ref(), full_texel),
                _ => {
                    let finer = &levels[l - 1];
                    (&finer.d[latest[l - 1]], finer.rate.as_ref(), finer.texel())
                }
            };
            self.coarse_down(down, level, source, rate, texel, timer)?;
            let end = starts.get(l + 1).copied().unwrap_or(schedule.steps);
            let steps = (l as u32 + 1, starts[l], end);
            latest[l] = self.coarse_steps(schedule, targets.layout, level, steps, timer)?;
        }
        for l in (1..levels.len()).rev() {
            let (finer, coarse) = (&levels[l - 1], &levels[l]);
            let out = 1 - latest[l - 1];
            self.coarse_blend(
                blend,
                &BlendInputs {
                    fine: &finer.d[latest[l - 1]],
                    fine_rate: finer.rate.as_ref(),
                    coarse,
                    coarse_latest: latest[l],
                    level: l as u32 + 1,
                    start: starts[l],
                },
                &finer.step[out],
                schedule,
                timer,
            )?;
            latest[l - 1] = out;
        }
        Ok(BlendInputs {
            fine: &targets.f[current],
            fine_rate: targets.rate.as_ref(),
            coarse: &levels[0],
            coarse_latest: latest[0],
            level: 1,
            start,
        })
    }

    /// A coarse level's down pass (program `p`): `source` and `rate` (a finer level's,
    /// `texel` = 1 / its size; no rate in the offset layout, where it is `source`'s alpha)
    /// averaged over 2x2 blocks into the level's D, D(kℓ) and rate.
    fn coarse_down(
        &self,
        p: &Program,
        level: &Level,
        source: &Texture,
        rate: Option<&Texture>,
        texel: [f32; 2],
        timer: &mut PassTimer,
    ) -> Result<()> {
        let gl = &self.gl;
        timer.pass(|| {
            level.down.bind_for_drawing();
            self.use_program(p);
            source.bind(UNIT_MAIN);
            if let Some(rate) = rate {
                rate.bind(UNIT_DEPTH);
            }
            set_int(gl, p, "u_f", UNIT_MAIN as i32);
            set_int(gl, p, "u_rate", UNIT_DEPTH as i32);
            set_value(gl, p, "u_texel", UniformValue::Vec2(texel));
            draw_fullscreen(gl);
        })
    }

    /// Steps `start..end` at coarse level `index` (1: half resolution), `(index, start,
    /// end)`, its D ping-ponged from `D[0]` (the down pass's output) in `layout`. Returns
    /// the D target holding the result.
    fn coarse_steps(
        &self,
        schedule: &Schedule,
        layout: Layout,
        level: &Level,
        (index, start, end): (u32, u32, u32),
        timer: &mut PassTimer,
    ) -> Result<usize> {
        let gl = &self.gl;
        let law = schedule.offset_law();
        let d = self.compiled(ProgramKey::Diffuse {
            matched: law.matched,
            layout,
        })?;
        // Offsets in the level's texels: the law's scale divided by 2^ℓ (module docs of
        // coarse.rs: exact in variance for the matched law), less what the level's
        // resampling adds (`Schedule::level_scale`).
        let factor = (schedule.level_scale(index, start, end) / f64::from(1u32 << index)) as f32;
        let texel = level.texel();
        let mut current = 0;
        for k in start..end {
            let (src, dst) = (current, 1 - current);
            timer.pass(|| {
                level.step[dst].bind_for_drawing();
                self.use_program(d);
                level.d[src].bind(UNIT_MAIN);
                if let Some(rate) = &level.rate {
                    rate.bind(UNIT_DEPTH);
                }
                let [scale, coefficient] = law.uniform(k);
                set_int(gl, d, "u_f", UNIT_MAIN as i32);
                set_int(gl, d, "u_rate", UNIT_DEPTH as i32);
                set_value(
                    gl,
                    d,
                    "u_law",
                    UniformValue::Vec2([factor * scale, coefficient]),
                );
                set_value(gl, d, "u_texel", UniformValue::Vec2(texel));
                draw_fullscreen(gl);
            })?;
            current = dst;
        }
        Ok(current)
    }

    /// A coarse level's blend (program `b`) into the finer level, drawn into
    /// `destination`.
    fn coarse_blend(
        &self,
        b: &Program,
        inputs: &BlendInputs,
        destination: &Framebuffer,
        schedule: &Schedule,
        timer: &mut PassTimer,
    ) -> Result<()> {
        timer.pass(|| {
            destination.bind_for_drawing();
            self.use_program(b);
            self.bind_blend(b, inputs, schedule);
            draw_fullscreen(&self.gl);
        })
    }

    /// Binds what a blend reads (`coarse_detail.glsl`) for `program`, in use.
    fn bind_blend(&self, program: &Program, inputs: &BlendInputs, schedule: &Schedule) {
        let gl = &self.gl;
        let decay = level_detail_decay(inputs.level) * schedule.sigma0 * schedule.sigma0;
        inputs.fine.bind(UNIT_MAIN);
        if let Some(rate) = inputs.fine_rate {
            rate.bind(UNIT_BLEND_RATE);
        }
        inputs.coarse.d[inputs.coarse_latest].bind(UNIT_SECOND);
        inputs.coarse.d0.bind(UNIT_BLEND_START);
        set_int(gl, program, "u_f", UNIT_MAIN as i32);
        set_int(gl, program, "u_rate", UNIT_BLEND_RATE as i32);
        set_int(gl, program, "u_coarse", UNIT_SECOND as i32);
        set_int(gl, program, "u_coarse0", UNIT_BLEND_START as i32);
        set_value(
            gl,
            program,
            "u_half_texel",
            UniformValue::Vec2(inputs.coarse.texel()),
        );
        set_value(
            gl,
            program,
            "u_detail",
            UniformValue::Vec3([
                decay as f32,
                2.0 * schedule.steps as f32,
                2.0 * inputs.start as f32,
            ]),
        );
    }
}

/// What a coarse level's blend reads.
struct BlendInputs<'a> {
    /// The finer level's D (or F) at the coarse level's first step.
    fine: &'a Texture,
    /// The finer level's rate (none in the offset layout: `fine`'s alpha).
    fine_rate: Option<&'a Texture>,
    /// The coarse level, and which of its D targets holds D at step N.
    coarse: &'a Level,
    coarse_latest: usize,
    /// Its index (1: half resolution) and first step.
    level: u32,
    start: u32,
}
