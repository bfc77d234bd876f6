//! A procedural outdoor scene rendered by brume's own GL code: a real frame (colour, a
//! non-linear depth buffer and its camera) for the engine fogs to work on (papers 001 and
//! 003), where a game would hand over the frame it has just drawn.
//!
//! **The scene** ([`Scene::default`], metres, y up; generated once on the CPU as indexed
//! triangles):
//! - a square ground plane at y = 0, 3 km on a side around the origin (past the far plane
//!   of [`Camera::default`] in every direction): grass and patches of earth with a checker
//!   of 2 m and 10 m squares, so that a blur shows;
//! - a lake in the ground plane (also y = 0), straight ahead of the default view and to
//!   its left: centre (x, z) = (−20, −95), radii 55 × 70 m with a wavy shore, from 26 m
//!   to 166 m away, between bearings 53° left and 26° right of −z; its water has four
//!   sine waves moving with `time` and reflects the sky (Fresnel, F₀ = 0.02), and it has
//!   a thin sandy shore;
//! - [`geometry::OBJECT_COUNT`] boxes and pillars (tall thin boxes) placed from a
//!   SplitMix64 seed, their centres 3 to 900 m from the origin, three in four within ±55°
//!   of −z (the default view), larger the farther they are so that the far ones stay
//!   visible (towers of 50-100 m at 900 m); Lambert + ambient shading, with a contact
//!   shadow at the foot of their walls; none rises more than 21.8° above the horizon
//!   seen from the default eye (0, 1.7, 0), so the top of a level default view is sky;
//! - the sun toward azimuth 120° (from −z toward +x, as a camera's yaw: behind the default
//!   camera, to its right), elevation 35°: the unit vector (0.709, 0.574, 0.410);
//!   no shadows;
//! - a sky where nothing else is: a vertical gradient by view direction, brightest at the
//!   horizon, a glow around the sun and its disc (0.6° radius).
//!
//! **The frame.** [`SceneRenderer::render`] draws into its own targets: a colour texture
//! (`RGBA16F`, linear light, not sRGB-encoded; alpha 1) and a depth texture
//! (`DEPTH_COMPONENT32F`, `NEAREST` filters, `TEXTURE_COMPARE_MODE` `NONE`, so that a pass
//! can `texelFetch` it), holding the standard GL window depth in [0, 1] of
//! `camera.projection(width / height) * camera.view_matrix()` (depth range 0..1), and 1.0
//! exactly where only the sky is. Pixel (x, y) is texel (x, y), row 0 at the bottom as
//! GL stores it, which is [`Camera`]'s convention: `camera.world_position(x, y, w, h, d)`
//! rebuilds the point a texel shows. Its linear values are about 0 to 1 (a white wall
//! facing the sun ≈ 1); the sun's disc is 30-40. No multisampling: each pixel is its
//! centre's surface, so the depth is exact where [`Scene::ray_cast`] meets it.
//!
//! **Drawing.** Three draw calls: the objects (one indexed draw, nearest first), the
//! ground (one indexed draw), then the sky, one triangle over the viewport at the far
//! plane (z = w) with the depth test `LEQUAL` and no depth writes, so that it is shaded
//! only where the depth kept its clear value 1.0. About 45 ms for 1920x1080 on llvmpipe
//! with two cores (90 ms of CPU time on one thread for a view full of ground).
//!
//! **The host's contract.** As for [`crate::pipeline`]: the context is current on the
//! calling thread for [`SceneRenderer::new`], every call and the drop (GLES 3.0 or later;
//! the colour target needs `EXT_color_buffer_half_float` or `EXT_color_buffer_float`, and
//! [`SceneFrame::read_depth`] needs `EXT_color_buffer_float`, which Mesa has).
//!
//! **GL state.** A render binds its own framebuffer, programs and vertex array, sets the
//! viewport to the frame, the depth range to (0, 1), the depth function to `LESS` and the
//! depth and colour masks to all on; it disables `BLEND`, `STENCIL_TEST`,
//! `SCISSOR_TEST`, `CULL_FACE`, `POLYGON_OFFSET_FILL`, `RASTERIZER_DISCARD`,
//! `SAMPLE_ALPHA_TO_COVERAGE` and `SAMPLE_COVERAGE`, enables `DEPTH_TEST` for the
//! geometry and disables it again after. On return: framebuffer binding (draw and read)
//! 0, no program, no vertex array, no `ARRAY_BUFFER`, `DEPTH_TEST` disabled, the other
//! capabilities above disabled, the viewport the frame's, the depth function `LESS`.
//! [`SceneFrame::read_depth`] also binds the depth texture on unit 0 (and no sampler
//! object) for its copy pass and unbinds it; both reads unbind `PIXEL_PACK_BUFFER`. The
//! active texture unit is `TEXTURE0` after any call. Clear values, blend functions and
//! pixel-store state are not touched.

pub mod geometry;

use crate::camera::Camera;
use crate::caps::Capabilities;
use crate::error::{Error, Result};
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::program::Program;
use crate::gpu::texture::{f32_bytes, Filter, TexelFormat, Texture};
use crate::gpu::{check_gl, object_created, object_deleted};
use crate::raster::{Grid, RgbImage, ScalarMap};
pub use geometry::{Hit, Lake, ObjectKind, Scene, SceneObject, Surface};
use geometry::{MeshData, VERTEX_FLOATS};
use glow::HasContext;
use std::sync::Arc;

const PRELUDE_GLSL: &str = include_str!("../../glsl/prelude.glsl");
const LIGHT_GLSL: &str = include_str!("../../glsl/scene/light.glsl");
const MESH_VERT: (&str, &str) = (
    "scene/mesh.vert",
    include_str!("../../glsl/scene/mesh.vert"),
);
const OBJECT_FRAG: (&str, &str) = (
    "scene/object.frag",
    include_str!("../../glsl/scene/object.frag"),
);
const GROUND_FRAG: (&str, &str) = (
    "scene/ground.frag",
    include_str!("../../glsl/scene/ground.frag"),
);
const SKY_VERT: (&str, &str) = ("scene/sky.vert", include_str!("../../glsl/scene/sky.vert"));
const SKY_FRAG: (&str, &str) = ("scene/sky.frag", include_str!("../../glsl/scene/sky.frag"));
const DEPTH_COPY_FRAG: (&str, &str) = (
    "scene/depth_copy.frag",
    include_str!("../../glsl/scene/depth_copy.frag"),
);

/// Capabilities disabled while the scene draws (module docs).
const DISABLED: [u32; 8] = [
    glow::BLEND,
    glow::STENCIL_TEST,
    glow::SCISSOR_TEST,
    glow::CULL_FACE,
    glow::POLYGON_OFFSET_FILL,
    glow::RASTERIZER_DISCARD,
    glow::SAMPLE_ALPHA_TO_COVERAGE,
    glow::SAMPLE_COVERAGE,
];

/// The water's clock wraps every hour (s), so that `time` as f32 keeps its precision.
const TIME_PERIOD: f64 = 3600.0;

/// The scene's vertex array with its vertex and index buffers: three GL objects, deleted
/// in Drop.
struct Mesh {
    gl: Arc<glow::Context>,
    vao: glow::VertexArray,
    vertices: glow::Buffer,
    indices: glow::Buffer,
    /// Index count of the objects, then of the ground (which follows them).
    objects: usize,
    ground: usize,
}

impl Mesh {
    fn new(gl: &Arc<glow::Context>, data: &MeshData) -> Result<Self> {
        let index_bytes: Vec<u8> = data.indices.iter().flat_map(|i| i.to_ne_bytes()).collect();
        // SAFETY: object creation and upload on the current context; each object is owned
        // by `mesh` as soon as it exists, so an error below deletes what was made.
        unsafe {
            let vao = gl.create_vertex_array().map_err(Error::Gl)?;
            object_created();
            let vertices = match gl.create_buffer() {
                Ok(b) => b,
                Err(e) => {
                    gl.delete_vertex_array(vao);
                    object_deleted();
                    return Err(Error::Gl(e));
                }
            };
            object_created();
            let indices = match gl.create_buffer() {
                Ok(b) => b,
                Err(e) => {
                    gl.delete_vertex_array(vao);
                    gl.delete_buffer(vertices);
                    object_deleted();
                    object_deleted();
                    return Err(Error::Gl(e));
                }
            };
            object_created();
            let mesh = Mesh {
                gl: Arc::clone(gl),
                vao,
                vertices,
                indices,
                objects: data.objects,
                ground: data.ground,
            };
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vertices));
            gl.buffer_data_u8_slice(
                glow::ARRAY_BUFFER,
                f32_bytes(&data.vertices),
                glow::STATIC_DRAW,
            );
            gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(indices));
            gl.buffer_data_u8_slice(glow::ELEMENT_ARRAY_BUFFER, &index_bytes, glow::STATIC_DRAW);
            let stride = (VERTEX_FLOATS * 4) as i32;
            for (location, size, offset) in [(0, 3, 0), (1, 3, 3), (2, 4, 6)] {
                gl.enable_vertex_attrib_array(location);
                gl.vertex_attrib_pointer_f32(
                    location,
                    size,
                    glow::FLOAT,
                    false,
                    stride,
                    offset * 4,
                );
            }
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, None);
            check_gl(gl, "uploading the scene's vertices")?;
            Ok(mesh)
        }
    }

    /// Draws `count` indices from index `first` with the bound program.
    fn draw(&self, first: usize, count: usize) {
        // SAFETY: the VAO is bound and its index buffer holds first + count indices.
        unsafe {
            self.gl.draw_elements(
                glow::TRIANGLES,
                count as i32,
                glow::UNSIGNED_INT,
                (first * 4) as i32,
            )
        };
    }
}

impl Drop for Mesh {
    fn drop(&mut self) {
        // SAFETY: the objects belong to this mesh; the context outlives it (Arc).
        unsafe {
            self.gl.delete_vertex_array(self.vao);
            self.gl.delete_buffer(self.vertices);
            self.gl.delete_buffer(self.indices);
        }
        for _ in 0..3 {
            object_deleted();
        }
    }
}

/// The render targets of one frame size, kept between frames.
struct Targets {
    // Field order is drop order: framebuffers before their textures.
    scene: Framebuffer,
    depth_copy: Option<(Framebuffer, Texture)>,
    colour: Texture,
    depth: Texture,
    width: usize,
    height: usize,
}

impl Targets {
    fn new(
        gl: &Arc<glow::Context>,
        caps: &Capabilities,
        width: usize,
        height: usize,
    ) -> Result<Self> {
        let colour = Texture::new(
            gl,
            width,
            height,
            TexelFormat::Rgba16F,
            Filter::Nearest,
            None,
        )?;
        let depth = Texture::new(
            gl,
            width,
            height,
            TexelFormat::Depth32F,
            Filter::Nearest,
            None,
        )?;
        let scene = Framebuffer::with_depth(
            gl,
            &[colour.raw()],
            Some(depth.raw()),
            width,
            height,
            "the scene",
        )?;
        let depth_copy = if caps.color_buffer_float {
            let copy = Texture::new(gl, width, height, TexelFormat::R32F, Filter::Nearest, None)?;
            let fbo = Framebuffer::over(gl, &[&copy], "the scene's depth read-back")?;
            Some((fbo, copy))
        } else {
            None
        };
        Ok(Targets {
            scene,
            depth_copy,
            colour,
            depth,
            width,
            height,
        })
    }
}

/// Renders [`Scene`] on a host's GL context (see the module docs for the contract).
pub struct SceneRenderer {
    // Field order is drop order; `gl` last, as the objects above need it.
    targets: Option<Targets>,
    objects: Program,
    ground: Program,
    sky: Program,
    depth_copy: Program,
    mesh: Mesh,
    scene: Scene,
    caps: Capabilities,
    gl: Arc<glow::Context>,
}

impl SceneRenderer {
    /// Builds the renderer of [`Scene::default`] on `gl`, current on this thread (GLES 3.0
    /// or later): compiles its programs and uploads the geometry.
    pub fn new(gl: Arc<glow::Context>) -> Result<Self> {
        Self::with_scene(gl, Scene::default())
    }

    /// The same for another scene (another seed of [`Scene::generate`], or one edited).
    pub fn with_scene(gl: Arc<glow::Context>, scene: Scene) -> Result<Self> {
        let caps = Capabilities::detect(&gl);
        if caps.gles_version.0 < 3 {
            return Err(Error::MissingCapability {
                capability: "OpenGL ES 3.0".into(),
                renderer: caps.renderer.clone(),
                hint: format!("the context is {}; brume needs GLES 3.x", caps.version),
            });
        }
        if !(caps.color_buffer_float || caps.color_buffer_half_float) {
            return Err(Error::MissingCapability {
                capability: "GL_EXT_color_buffer_half_float".into(),
                renderer: caps.renderer.clone(),
                hint: "the scene's RGBA16F colour target cannot be rendered to".into(),
            });
        }
        // As in the pipeline: GLSL ES 3.20 only on a GLES 3.2 context.
        let version = if gl.version().is_embedded && caps.gles_version >= (3, 2) {
            "#version 320 es"
        } else {
            "#version 300 es"
        };
        let plain = format!("{version}\n{PRELUDE_GLSL}");
        let lit = format!("{plain}\n{LIGHT_GLSL}");
        let objects = Program::with_vertex(
            &gl,
            (&plain, MESH_VERT),
            (&lit, OBJECT_FRAG),
            &["u_view_projection", "u_sun_direction"],
            &[],
        )?;
        let ground = Program::with_vertex(
            &gl,
            (&plain, MESH_VERT),
            (&lit, GROUND_FRAG),
            &[
                "u_view_projection",
                "u_sun_direction",
                "u_eye",
                "u_time",
                "u_lake_centre",
                "u_lake_radii",
            ],
            &[],
        )?;
        let sky = Program::with_vertex(
            &gl,
            (&plain, SKY_VERT),
            (&lit, SKY_FRAG),
            &["u_forward", "u_right", "u_up", "u_sun_direction"],
            &[],
        )?;
        let depth_copy = Program::new(&gl, &plain, DEPTH_COPY_FRAG, &["u_depth"], &[])?;
        let mesh = Mesh::new(&gl, &MeshData::new(&scene))?;
        Ok(SceneRenderer {
            targets: None,
            objects,
            ground,
            sky,
            depth_copy,
            mesh,
            scene,
            caps,
            gl,
        })
    }

    /// The scene drawn.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The driver's capabilities, detected once.
    pub fn caps(&self) -> &Capabilities {
        &self.caps
    }

    /// Renders the scene seen by `camera` into this renderer's colour and depth textures
    /// of `width x height` (kept for the next frame of the same size; see the module docs
    /// for their content and the GL state). `time` (s) moves the water's waves.
    pub fn render(
        &mut self,
        camera: &Camera,
        width: usize,
        height: usize,
        time: f64,
    ) -> Result<SceneFrame<'_>> {
        camera.validate()?;
        self.caps.require_size("scene frame", width, height)?;
        if !time.is_finite() {
            return Err(Error::invalid("time", time, "a finite time in seconds"));
        }
        if self
            .targets
            .as_ref()
            .is_none_or(|t| (t.width, t.height) != (width, height))
        {
            self.targets = None;
            self.targets = Some(Targets::new(&self.gl, &self.caps, width, height)?);
        }
        let targets = self.targets.as_ref().expect("targets were just made");
        self.draw(targets, camera, width, height, time);
        self.leave_state();
        check_gl(&self.gl, "rendering the scene")?;
        Ok(SceneFrame {
            colour: targets.colour.raw(),
            depth: targets.depth.raw(),
            width,
            height,
            camera: *camera,
            renderer: self,
        })
    }

    fn draw(&self, targets: &Targets, camera: &Camera, width: usize, height: usize, time: f64) {
        let gl = &self.gl;
        let aspect = width as f64 / height as f64;
        let view_projection = (camera.projection(aspect) * camera.view_matrix())
            .as_mat4()
            .to_cols_array();
        let sun = self.scene.sun_direction.map(|v| v as f32);
        let eye = camera.eye().as_vec3();
        let ray_y = (camera.fov_y_deg.to_radians() / 2.0).tan();
        let forward = camera.forward().as_vec3();
        let right = (camera.right() * (ray_y * aspect)).as_vec3();
        let up = (camera.up() * ray_y).as_vec3();
        let lake = self.scene.lake;
        let time = time.rem_euclid(TIME_PERIOD) as f32;
        // SAFETY: state changes and draws on the current context with owned objects; the
        // uniforms set are those each program declares, with the types its shaders use.
        unsafe {
            targets.scene.bind_for_drawing();
            for cap in DISABLED {
                gl.disable(cap);
            }
            gl.color_mask(true, true, true, true);
            gl.depth_mask(true);
            gl.depth_range_f32(0.0, 1.0);
            gl.depth_func(glow::LESS);
            gl.clear_buffer_f32_slice(glow::COLOR, 0, &[0.0, 0.0, 0.0, 1.0]);
            gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[1.0]);
            gl.bind_vertex_array(Some(self.mesh.vao));

            gl.enable(glow::DEPTH_TEST);
            let p = &self.objects;
            gl.use_program(Some(p.raw()));
            gl.uniform_matrix_4_f32_slice(
                Some(p.uniform("u_view_projection")),
                false,
                &view_projection,
            );
            gl.uniform_3_f32_slice(Some(p.uniform("u_sun_direction")), &sun);
            self.mesh.draw(0, self.mesh.objects);

            let p = &self.ground;
            gl.use_program(Some(p.raw()));
            gl.uniform_matrix_4_f32_slice(
                Some(p.uniform("u_view_projection")),
                false,
                &view_projection,
            );
            gl.uniform_3_f32_slice(Some(p.uniform("u_sun_direction")), &sun);
            gl.uniform_3_f32_slice(Some(p.uniform("u_eye")), &eye.to_array());
            gl.uniform_1_f32(Some(p.uniform("u_time")), time);
            let [cx, cz] = lake.centre.map(|v| v as f32);
            let [rx, rz] = lake.radii.map(|v| v as f32);
            gl.uniform_2_f32(Some(p.uniform("u_lake_centre")), cx, cz);
            gl.uniform_2_f32(Some(p.uniform("u_lake_radii")), rx, rz);
            self.mesh.draw(self.mesh.objects, self.mesh.ground);

            // The sky last, at the far plane, where the depth is still 1.0: not written.
            gl.depth_func(glow::LEQUAL);
            gl.depth_mask(false);
            let p = &self.sky;
            gl.use_program(Some(p.raw()));
            gl.uniform_3_f32_slice(Some(p.uniform("u_forward")), &forward.to_array());
            gl.uniform_3_f32_slice(Some(p.uniform("u_right")), &right.to_array());
            gl.uniform_3_f32_slice(Some(p.uniform("u_up")), &up.to_array());
            gl.uniform_3_f32_slice(Some(p.uniform("u_sun_direction")), &sun);
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.depth_mask(true);
            gl.depth_func(glow::LESS);
            gl.disable(glow::DEPTH_TEST);
        }
    }

    /// Copies the depth texture into the R32F target (a full-screen `texelFetch` pass).
    fn copy_depth<'t>(&self, targets: &'t Targets) -> Result<&'t Framebuffer> {
        let Some((fbo, _)) = &targets.depth_copy else {
            return Err(Error::MissingCapability {
                capability: "GL_EXT_color_buffer_float".into(),
                renderer: self.caps.renderer.clone(),
                hint: "the depth is read back through an R32F target; use the depth texture \
                       on the GPU instead"
                    .into(),
            });
        };
        let gl = &self.gl;
        // SAFETY: state changes and one draw on the current context with owned objects.
        unsafe {
            fbo.bind_for_drawing();
            for cap in DISABLED {
                gl.disable(cap);
            }
            gl.disable(glow::DEPTH_TEST);
            gl.color_mask(true, true, true, true);
            gl.bind_vertex_array(Some(self.mesh.vao));
            gl.use_program(Some(self.depth_copy.raw()));
            gl.active_texture(glow::TEXTURE0);
            gl.bind_texture(glow::TEXTURE_2D, Some(targets.depth.raw()));
            gl.bind_sampler(0, None);
            gl.uniform_1_i32(Some(self.depth_copy.uniform("u_depth")), 0);
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
            gl.bind_texture(glow::TEXTURE_2D, None);
        }
        self.leave_state();
        check_gl(gl, "copying the scene's depth")?;
        Ok(fbo)
    }

    /// The state every call leaves (module docs).
    fn leave_state(&self) {
        let gl = &self.gl;
        // SAFETY: unbinding on the current context.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.use_program(None);
            gl.bind_vertex_array(None);
            gl.bind_buffer(glow::ARRAY_BUFFER, None);
            gl.active_texture(glow::TEXTURE0);
        }
    }
}

/// One rendered frame: the renderer's textures (valid until its next render or its drop)
/// and the camera that saw it.
pub struct SceneFrame<'a> {
    /// Linear RGB colour, `RGBA16F`, alpha 1.
    pub colour: glow::Texture,
    /// Window depth, `DEPTH_COMPONENT32F` (1.0 where only the sky is).
    pub depth: glow::Texture,
    /// Width (px).
    pub width: usize,
    /// Height (px).
    pub height: usize,
    /// The camera of the frame.
    pub camera: Camera,
    renderer: &'a SceneRenderer,
}

impl SceneFrame<'_> {
    fn targets(&self) -> &Targets {
        self.renderer
            .targets
            .as_ref()
            .expect("a frame exists only after its targets")
    }

    /// Reads the colour back: linear RGB, **row 0 at the bottom** as GL stores it, so
    /// that `get(x, y)` is pixel (x, y) of [`Camera`]'s convention (flip the rows for an
    /// image file, which starts at the top).
    pub fn read_colour(&self) -> Result<RgbImage> {
        unbind_pack_buffer(&self.renderer.gl);
        let rgba = self.targets().scene.read_rgba()?;
        let rgb = rgba.into_iter().map(|[r, g, b, _]| [r, g, b]).collect();
        Ok(Grid::from_vec(self.width, self.height, rgb))
    }

    /// Reads the window depth back (through a copy into an R32F target, exact): **row 0
    /// at the bottom** as GL stores it, like [`SceneFrame::read_colour`]. Needs
    /// `EXT_color_buffer_float`.
    pub fn read_depth(&self) -> Result<ScalarMap> {
        let fbo = self.renderer.copy_depth(self.targets())?;
        unbind_pack_buffer(&self.renderer.gl);
        Ok(Grid::from_vec(self.width, self.height, fbo.read_red()?))
    }
}

/// A pixel-pack buffer bound by the host would turn a read into an offset into it.
fn unbind_pack_buffer(gl: &glow::Context) {
    // SAFETY: unbinding on the current context.
    unsafe { gl.bind_buffer(glow::PIXEL_PACK_BUFFER, None) };
}
