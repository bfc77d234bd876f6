//! Uniforms and lookups: the medium's values, the pipeline's `brume_*` and the camera's
//! constants, the medium's lookup textures, and the setters every pass uses.

use super::{Input, Pipeline, UNIT_LOOKUP};
use crate::error::{Error, Result};
use crate::gpu::program::Program;
use crate::gpu::texture::{Filter, TexelFormat, Texture};
use crate::medium::{Lookup, Medium, UniformValue, Wrap, MAX_LOOKUPS};
use glow::HasContext;
use std::sync::Arc;

impl Pipeline {
    /// Sets the medium's uniforms, the pipeline's `brume_*` ones and the camera's, and
    /// binds the medium's lookups, for the bound program `p`.
    pub(super) fn set_medium_uniforms(
        &self,
        p: &Program,
        medium: &dyn Medium,
        input: &Input,
        sigma0: f64,
    ) {
        let gl = &self.gl;
        set_value(gl, p, "brume_sigma0", UniformValue::Float(sigma0 as f32));
        set_value(
            gl,
            p,
            "brume_size",
            UniformValue::IVec2([input.width as i32, input.height as i32]),
        );
        for (name, value) in camera_uniforms(medium, input) {
            set_value(gl, p, name, value);
        }
        for (name, value) in medium.uniforms(&input.frame) {
            set_value(gl, p, &name, value);
        }
        for (unit, (name, lookup)) in (UNIT_LOOKUP..).zip(medium.lookups()) {
            if let Some(texture) = self.lookups.get(&lookup.id()) {
                texture.bind(unit);
                set_int(gl, p, &name, unit as i32);
            }
        }
    }

    /// Uploads the medium's lookups not yet on the GPU, and frees those of earlier media.
    pub(super) fn upload_lookups(&mut self, medium: &dyn Medium) -> Result<()> {
        let lookups = medium.lookups();
        if lookups.len() > MAX_LOOKUPS {
            return Err(Error::Gl(format!(
                "glsl/medium/{}.glsl: {} lookup textures, at most {MAX_LOOKUPS}",
                medium.name(),
                lookups.len()
            )));
        }
        self.lookups
            .retain(|id, _| lookups.iter().any(|(_, l)| l.id() == *id));
        for (_, lookup) in lookups {
            if !self.lookups.contains_key(&lookup.id()) {
                let texture = upload_lookup(&self.gl, &lookup)?;
                self.lookups.insert(lookup.id(), texture);
            }
        }
        Ok(())
    }
}

/// The camera's per-frame constants (see [`crate::camera`]) for the medium and the
/// frame of `input`; zero without a camera.
fn camera_uniforms(medium: &dyn Medium, input: &Input) -> [(&'static str, UniformValue); 3] {
    let (rays, constants, eye) = match medium.frame_camera(&input.frame) {
        Some(camera) => {
            let camera = camera.for_frame(input.width, input.height);
            let mut rays = [0f32; 9];
            for (i, ray) in camera.corner_rays().iter().enumerate() {
                rays[3 * i..3 * i + 3].copy_from_slice(&ray.as_vec3().to_array());
            }
            (
                rays,
                camera.shader_depth_constants().map(|v| v as f32),
                camera.eye().as_vec3().to_array(),
            )
        }
        None => ([0.0; 9], [0.0; 4], [0.0; 3]),
    };
    [
        ("brume_corner_rays", UniformValue::Mat3(rays)),
        ("brume_depth_constants", UniformValue::Vec4(constants)),
        ("brume_eye", UniformValue::Vec3(eye)),
    ]
}

/// A lookup as an `R32F` bilinear texture with its wrap mode.
fn upload_lookup(gl: &Arc<glow::Context>, lookup: &Lookup) -> Result<Texture> {
    let texture = Texture::new(
        gl,
        lookup.width(),
        lookup.height(),
        match lookup.channels() {
            3 => TexelFormat::Rgb32F,
            _ => TexelFormat::R32F,
        },
        Filter::Linear,
        Some(lookup.values()),
    )?;
    if lookup.wrap() == Wrap::Repeat {
        texture.set_repeat();
    }
    Ok(texture)
}

/// Sets a uniform of the bound program `p` if the program uses it.
pub(super) fn set_value(gl: &glow::Context, p: &Program, name: &str, value: UniformValue) {
    let Some(location) = p.optional_uniform(name) else {
        return;
    };
    let location = Some(location);
    // SAFETY: a uniform of the bound program, with the type the shader declares.
    unsafe {
        match value {
            UniformValue::Float(v) => gl.uniform_1_f32(location, v),
            UniformValue::Vec2([a, b]) => gl.uniform_2_f32(location, a, b),
            UniformValue::Vec3([a, b, c]) => gl.uniform_3_f32(location, a, b, c),
            UniformValue::Vec4([a, b, c, d]) => gl.uniform_4_f32(location, a, b, c, d),
            UniformValue::Int(v) => gl.uniform_1_i32(location, v),
            UniformValue::IVec2([a, b]) => gl.uniform_2_i32(location, a, b),
            UniformValue::IVec3([a, b, c]) => gl.uniform_3_i32(location, a, b, c),
            UniformValue::IVec4([a, b, c, d]) => gl.uniform_4_i32(location, a, b, c, d),
            UniformValue::Mat3(m) => gl.uniform_matrix_3_f32_slice(location, false, &m),
        }
    }
}

pub(super) fn set_int(gl: &glow::Context, p: &Program, name: &str, value: i32) {
    if let Some(location) = p.optional_uniform(name) {
        // SAFETY: an int or sampler uniform of the bound program.
        unsafe { gl.uniform_1_i32(Some(location), value) };
    }
}

/// Binds a texture (brume's or the host's, by handle) to `unit`.
pub(super) fn bind_texture(gl: &glow::Context, unit: u32, texture: Option<glow::Texture>) {
    // SAFETY: binding a texture handle of the current context.
    unsafe {
        gl.active_texture(glow::TEXTURE0 + unit);
        gl.bind_texture(glow::TEXTURE_2D, texture);
    }
}
