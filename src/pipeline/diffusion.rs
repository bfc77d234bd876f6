//! The N + 2 passes of a render (module docs of the parent): the medium pass, the
//! diffusion steps and the composite.

use super::programs::{medium_key, ProgramKey};
use super::uniforms::{bind_texture, set_int, set_value};
use super::{
    draw_fullscreen, Destination, Encoding, Input, Pipeline, UNIT_DEPTH, UNIT_LOOKUP, UNIT_MAIN,
    UNIT_SECOND,
};
use crate::error::{Error, Result};
use crate::gpu::timer::PassTimer;
use crate::medium::{Medium, UniformValue};
use crate::schedule::{Schedule, DETAIL_DECAY};

impl Pipeline {
    /// The N + 2 passes (N + 4 with the coarse stage: its down and blend passes), timed
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
        let chromatic = targets.tau_gb.is_some();

        let p = self.compiled(medium_key(medium, targets.precision, schedule, chromatic))?;
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
            chromatic,
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
                targets.rate.bind(UNIT_DEPTH);
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
        if let Some(start) = self.coarse_start {
            current = self.run_coarse(schedule, start, current, timer)?;
        }

        let c = self.compiled(ProgramKey::Composite {
            medium: super::programs::MediumId::of(medium),
            chromatic,
        })?;
        let free = 1 - current;
        timer.pass(|| {
            let (origin, encoding) =
                self.bind_destination(destination, input, Some(&targets.step[free]));
            self.use_program(c);
            targets.f[current].bind(UNIT_MAIN);
            bind_texture(gl, UNIT_DEPTH, Some(input.depth));
            if let Some(pair) = &targets.tau_gb {
                pair[current].bind(UNIT_SECOND);
            }
            set_int(gl, c, "u_f", UNIT_MAIN as i32);
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

    /// The coarse stage (`coarse.rs`) from step `start`, F at `start` in target
    /// `current`: down, steps `start..N` at half resolution, blend into the other target.
    /// Returns the target that holds F at step N.
    fn run_coarse(
        &self,
        schedule: &Schedule,
        start: u32,
        current: usize,
        timer: &mut PassTimer,
    ) -> Result<usize> {
        let gl = &self.gl;
        let targets = self.targets()?;
        let (programs, half) = match (&self.coarse.programs, &self.coarse.targets) {
            (Some(p), Some(t)) => (p, t),
            _ => return Err(Error::Gl("internal: coarse stage not prepared".into())),
        };
        let full_texel = [1.0 / targets.width as f32, 1.0 / targets.height as f32];
        let half_texel = half.texel();
        timer.pass(|| {
            half.down.bind_for_drawing();
            self.use_program(&programs.down);
            targets.f[current].bind(UNIT_MAIN);
            targets.rate.bind(UNIT_DEPTH);
            set_int(gl, &programs.down, "u_f", UNIT_MAIN as i32);
            set_int(gl, &programs.down, "u_rate", UNIT_DEPTH as i32);
            set_value(
                gl,
                &programs.down,
                "u_texel",
                UniformValue::Vec2(full_texel),
            );
            draw_fullscreen(gl);
        })?;
        let law = schedule.offset_law();
        let d = self.compiled(ProgramKey::Diffuse {
            matched: law.matched,
            chromatic: false,
        })?;
        let shrink = schedule.coarse_scale(start) as f32;
        let mut coarse = 0;
        for k in start..schedule.steps {
            let (src, dst) = (coarse, 1 - coarse);
            timer.pass(|| {
                half.step[dst].bind_for_drawing();
                self.use_program(d);
                half.d[src].bind(UNIT_MAIN);
                half.rate.bind(UNIT_DEPTH);
                // Offsets in half-resolution texels: the law's scale halves (module docs
                // of coarse.rs: exact in variance for the matched law), less what the
                // resampling adds (`Schedule::coarse_scale`).
                let [scale, coefficient] = law.uniform(k);
                set_int(gl, d, "u_f", UNIT_MAIN as i32);
                set_int(gl, d, "u_rate", UNIT_DEPTH as i32);
                set_value(
                    gl,
                    d,
                    "u_law",
                    UniformValue::Vec2([0.5 * shrink * scale, coefficient]),
                );
                set_value(gl, d, "u_texel", UniformValue::Vec2(half_texel));
                draw_fullscreen(gl);
            })?;
            coarse = dst;
        }
        let out = 1 - current;
        let b = &programs.blend;
        timer.pass(|| {
            targets.step[out].bind_for_drawing();
            self.use_program(b);
            targets.f[current].bind(UNIT_MAIN);
            targets.rate.bind(UNIT_DEPTH);
            half.d[coarse].bind(UNIT_SECOND);
            half.d0.bind(UNIT_LOOKUP);
            set_int(gl, b, "u_f", UNIT_MAIN as i32);
            set_int(gl, b, "u_rate", UNIT_DEPTH as i32);
            set_int(gl, b, "u_coarse", UNIT_SECOND as i32);
            set_int(gl, b, "u_coarse0", UNIT_LOOKUP as i32);
            set_value(gl, b, "u_half_texel", UniformValue::Vec2(half_texel));
            let decay = DETAIL_DECAY * schedule.sigma0 * schedule.sigma0;
            set_value(
                gl,
                b,
                "u_detail",
                UniformValue::Vec3([
                    decay as f32,
                    2.0 * schedule.steps as f32,
                    2.0 * start as f32,
                ]),
            );
            draw_fullscreen(gl);
        })?;
        Ok(out)
    }
}
