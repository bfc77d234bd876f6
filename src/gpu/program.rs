//! Shader programs built from the `.glsl` files in `glsl/`, with the `#version` line chosen
//! at run time for the context (320 es, or 300 es on a GLES 3.0/3.1 driver) and any
//! `#define`s that specialise a file (`diffuse.frag`'s `VARIANCE_MATCHED`).

use crate::error::{Error, Result};
use glow::HasContext;
use std::collections::HashMap;
use std::sync::Arc;

/// The vertex shader every pass shares: one triangle that covers the viewport.
pub const FULLSCREEN_VERT: (&str, &str) = (
    "fullscreen.vert",
    include_str!("../../glsl/fullscreen.vert"),
);

/// A linked program and its uniform locations, looked up once.
pub struct Program {
    gl: Arc<glow::Context>,
    raw: glow::Program,
    name: String,
    uniforms: HashMap<String, glow::UniformLocation>,
}

impl Program {
    /// Compiles `fragment` (file name and source, without `#version`) with the shared
    /// vertex shader and links them; `header` goes before each source: the `#version`
    /// line, then any `#define`s. Errors carry the file name and the driver's log.
    /// `uniforms` must be active in the program; `optional` ones may have been optimised
    /// out (a medium's uniforms in a pass that needs only part of the medium).
    pub fn new(
        gl: &Arc<glow::Context>,
        header: &str,
        fragment: (&str, &str),
        uniforms: &[&'static str],
        optional: &[&str],
    ) -> Result<Self> {
        Self::with_vertex(
            gl,
            (header, FULLSCREEN_VERT),
            (header, fragment),
            uniforms,
            optional,
        )
    }

    /// The same with a vertex shader of its own: each stage is `(header, (file name,
    /// source))`, the header put before the source (the stages may differ in `#define`s
    /// or shared code). Errors name the failing file, or the fragment file for a link
    /// error.
    pub fn with_vertex(
        gl: &Arc<glow::Context>,
        (vertex_header, vertex): (&str, (&str, &str)),
        (header, fragment): (&str, (&str, &str)),
        uniforms: &[&'static str],
        optional: &[&str],
    ) -> Result<Self> {
        // SAFETY: standard shader/program creation on the current context; every object
        // created here is deleted on the error paths or owned by the returned Program.
        unsafe {
            let raw = gl.create_program().map_err(Error::Gl)?;
            let vert = compile(gl, vertex_header, glow::VERTEX_SHADER, vertex);
            let frag = compile(gl, header, glow::FRAGMENT_SHADER, fragment);
            let (vert, frag) = match (vert, frag) {
                (Ok(v), Ok(f)) => (v, f),
                (v, f) => {
                    for shader in [v.as_ref().ok(), f.as_ref().ok()].into_iter().flatten() {
                        gl.delete_shader(*shader);
                    }
                    gl.delete_program(raw);
                    return Err(v.err().or(f.err()).expect("one shader failed"));
                }
            };
            gl.attach_shader(raw, vert);
            gl.attach_shader(raw, frag);
            gl.link_program(raw);
            let linked = gl.get_program_link_status(raw);
            let log = gl.get_program_info_log(raw);
            gl.detach_shader(raw, vert);
            gl.detach_shader(raw, frag);
            gl.delete_shader(vert);
            gl.delete_shader(frag);
            if !linked {
                gl.delete_program(raw);
                return Err(Error::Shader {
                    name: fragment.0.to_string(),
                    stage: "link",
                    log,
                });
            }
            let mut found = HashMap::new();
            // Owned from here: an error below deletes the program in Drop.
            super::object_created();
            let mut program = Program {
                gl: Arc::clone(gl),
                raw,
                name: fragment.0.to_string(),
                uniforms: HashMap::new(),
            };
            for &u in uniforms {
                let loc = gl.get_uniform_location(raw, u).ok_or_else(|| {
                    Error::Gl(format!(
                        "{}: uniform {u} not found (unused or misspelled)",
                        fragment.0
                    ))
                })?;
                found.insert(u.to_string(), loc);
            }
            for &u in optional {
                if let Some(loc) = gl.get_uniform_location(raw, u) {
                    found.insert(u.to_string(), loc);
                }
            }
            program.uniforms = found;
            Ok(program)
        }
    }

    /// The GL program object.
    pub fn raw(&self) -> glow::Program {
        self.raw
    }

    /// The shader file name, for messages.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The location of a uniform declared at construction. Panics on an undeclared name,
    /// which is a programming error caught by every test that renders.
    pub fn uniform(&self, name: &str) -> &glow::UniformLocation {
        self.uniforms
            .get(name)
            .unwrap_or_else(|| panic!("{}: uniform {name} was not declared", self.name))
    }

    /// The location of an optional uniform, `None` where the compiler removed it.
    pub fn optional_uniform(&self, name: &str) -> Option<&glow::UniformLocation> {
        self.uniforms.get(name)
    }
}

impl Drop for Program {
    fn drop(&mut self) {
        // SAFETY: the program belongs to this wrapper and the context outlives it (Arc).
        unsafe { self.gl.delete_program(self.raw) };
        super::object_deleted();
    }
}

unsafe fn compile(
    gl: &glow::Context,
    header: &str,
    kind: u32,
    (name, body): (&str, &str),
) -> Result<glow::Shader> {
    let shader = gl.create_shader(kind).map_err(Error::Gl)?;
    gl.shader_source(shader, &format!("{header}\n{body}"));
    gl.compile_shader(shader);
    if gl.get_shader_compile_status(shader) {
        Ok(shader)
    } else {
        let log = gl.get_shader_info_log(shader);
        gl.delete_shader(shader);
        Err(Error::Shader {
            name: name.to_string(),
            stage: "compile",
            log,
        })
    }
}
