//! The N + 2 passes of a render (module docs of the parent): the medium pass, the
//! diffusion steps and the composite.

use super::programs::{medium_key, ProgramKey};
use super::uniforms::{bind_texture, set_int, set_value};
use super::{
    draw_fullscreen, Destination, Encoding, Input, Pipeline, UNIT_DEPTH, UNIT_MAIN, UNIT_SECOND,
};
use crate::error::Result;
use crate::gpu::timer::PassTimer;
use crate::medium::{Medium, UniformValue};
use crate::schedule::Schedule;

impl Pipeline {
    /// The N + 2 passes, timed by `timer`; returns the ping-pong target that is free for
    /// an internal result.
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
        let mut current = 0;
        for k in 0..schedule.steps {
            let (src, dst) = (current, 1 - current);
            timer.pass(|| {
                targets.step[dst].bind_for_drawing();
                self.use_program(d);
                targets.f[src].bind(UNIT_MAIN);
                targets.rate.bind(UNIT_DEPTH);
                if let Some(pair) = &targets.tau_gb {
                    pair[src].bind(UNIT_SECOND);
                }
                let [scale, coefficient] = law.uniform(k);
                set_int(gl, d, "u_f", UNIT_MAIN as i32);
                set_int(gl, d, "u_rate", UNIT_DEPTH as i32);
                set_int(gl, d, "u_tau_gb", UNIT_SECOND as i32);
                set_value(gl, d, "u_law", UniformValue::Vec2([scale, coefficient]));
                set_value(gl, d, "u_texel", UniformValue::Vec2(texel));
                draw_fullscreen(gl);
            })?;
            current = dst;
        }

        let c = self.compiled(ProgramKey::Composite {
            medium: medium.name(),
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
}
