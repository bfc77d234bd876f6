//! `glsl/diffuse.frag` itself, in f32 on the GL driver, against the f64 schedule of
//! `src/schedule.rs` (`OffsetLaw::offset`, `bilinear_moment`): the offset law with its
//! Taylor series of sinh(ρ)/ρ, and one whole diffusion pass, measured where its result
//! isolates the offset.
//!
//! The shader is compiled here from its own file, with the `#defines` and the prelude the
//! pipeline gives it (src/pipeline/mod.rs, `Pipeline::compile`), not from a transcription.
//!
//! Tolerances follow from the GLSL ES 3.20 precision rules (sec. 4.7.1): `+`, `−`, `*` are
//! correctly rounded (½ ULP), `/` within 2.5 ULP, `exp(x)` within 3 + 2|x| ULP; an ULP of
//! an f32 is at most 2⁻²³ of its value.
use crate::common;

use brume::gpu::framebuffer::Framebuffer;
use brume::gpu::program::Program;
use brume::gpu::texture::{Filter, TexelFormat, Texture};
use brume::schedule::{bilinear_moment, OffsetLaw, Schedule, Scheme};
use glow::HasContext;
use std::sync::Arc;

const PRELUDE: &str = include_str!("../glsl/prelude.glsl");
const DIFFUSE: &str = include_str!("../glsl/diffuse.frag");

/// One ULP of an f32, relative to the value: 2⁻²³.
const ULP: f64 = 1.0 / 8_388_608.0;

/// The header `Pipeline::compile` puts before `diffuse.frag`: `#version`, the three
/// switches (a grey τ, ρ in a texture of its own or in F's alpha: `offset`), the prelude.
fn header(gl: &glow::Context, matched: bool, offset: bool) -> String {
    let version = if gl.version().is_embedded && gl.version().major * 10 + gl.version().minor >= 32
    {
        "#version 320 es"
    } else {
        "#version 300 es"
    };
    format!(
        "{version}\n#define VARIANCE_MATCHED {}\n#define CHROMATIC 0\n#define OFFSET_LAYOUT {}\n\
         {PRELUDE}",
        i32::from(matched),
        i32::from(offset)
    )
}

/// A GL context for the test, with an empty vertex array bound (GLES 3 draws need one).
struct Gl {
    _lock: std::sync::MutexGuard<'static, ()>,
    headless: brume::Headless,
    vao: glow::VertexArray,
}

impl Gl {
    fn open() -> Gl {
        let (lock, headless) = common::renderer();
        headless
            .context()
            .make_current()
            .expect("a current context");
        let gl = Arc::clone(headless.context().gl());
        // SAFETY: an empty VAO on the current context, deleted in Drop.
        let vao = unsafe { gl.create_vertex_array() }.expect("a vertex array");
        // SAFETY: binding the VAO just created.
        unsafe { gl.bind_vertex_array(Some(vao)) };
        Gl {
            _lock: lock,
            headless,
            vao,
        }
    }

    fn gl(&self) -> &Arc<glow::Context> {
        self.headless.context().gl()
    }

    /// Draws the full-screen triangle with `program` into `target`, `textures` on units
    /// 0, 1, …, named by their sampler uniforms, and returns the target's texels (RGBA,
    /// row 0 first).
    fn draw(
        &self,
        program: &Program,
        textures: &[(&str, &Texture)],
        law: [f32; 2],
        target: &Texture,
    ) -> Vec<[f32; 4]> {
        let gl = self.gl();
        let fb = Framebuffer::over(gl, &[target], "the test target").expect("a framebuffer");
        fb.bind_for_drawing();
        // SAFETY: the program, textures and uniforms are this test's, on the current context.
        unsafe {
            gl.use_program(Some(program.raw()));
            for (unit, (name, texture)) in textures.iter().enumerate() {
                texture.bind(unit as u32);
                gl.uniform_1_i32(Some(program.uniform(name)), unit as i32);
            }
            gl.uniform_2_f32(Some(program.uniform("u_law")), law[0], law[1]);
            if let Some(texel) = program.optional_uniform("u_texel") {
                let (w, h) = (target.width() as f32, target.height() as f32);
                gl.uniform_2_f32(Some(texel), 1.0 / w, 1.0 / h);
            }
            gl.draw_arrays(glow::TRIANGLES, 0, 3);
        }
        brume::gpu::check_gl(gl, "drawing the test pass").expect("no GL error");
        let texels = fb.read_rgba().expect("a read-back");
        // SAFETY: unbinding on the current context.
        unsafe {
            gl.use_program(None);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        }
        texels
    }
}

impl Drop for Gl {
    fn drop(&mut self) {
        // SAFETY: the test's own VAO, on its context.
        unsafe { self.gl().delete_vertex_array(self.vao) };
    }
}

/// sinh(ρ)/ρ in f64, with its limit 1 at 0.
fn sinhc(r: f64) -> f64 {
    if r == 0.0 {
        1.0
    } else {
        r.sinh() / r
    }
}

/// The shader's functions `sinhc`, `offset_at` and `offset_for_moment`, evaluated by the
/// driver: diffuse.frag's own text with its `main` renamed (kept, unused) and a `main` that
/// writes (sinhc(ρ), offset_at(ρ), offset_for_moment(m), 0) for a ρ from `u_rate` and an m
/// from `u_f`, texel by texel.
#[test]
fn the_shaders_offset_law_and_series_match_the_f64_schedule() {
    let gl = Gl::open();
    let opening = "void main() {";
    assert_eq!(DIFFUSE.matches(opening).count(), 1, "diffuse.frag's main");
    let probe = DIFFUSE.replace(opening, "void diffuse_main() {")
        + "
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float rate = texelFetch(u_rate, p, 0).r;
    float m = texelFetch(u_f, p, 0).r;
    o_f = vec4(sinhc(rate), offset_at(rate), offset_for_moment(m), 0.0);
}
";
    // 1024 rates over [0, ¼] (the whole range a schedule gives) and 1024 moments over
    // [0, 400] (offsets up to 20 px, across every integer boundary i² of m⁻¹).
    let (w, h) = (32usize, 32usize);
    let n = w * h;
    let rates: Vec<f32> = (0..n)
        .map(|i| (0.25 * i as f64 / (n - 1) as f64) as f32)
        .collect();
    let moments: Vec<f32> = (0..n)
        .map(|i| (400.0 * i as f64 / (n - 1) as f64) as f32)
        .collect();
    let g = gl.gl();
    let rate_tex = Texture::new(g, w, h, TexelFormat::R32F, Filter::Nearest, Some(&rates)).unwrap();
    let rgba: Vec<f32> = moments.iter().flat_map(|&m| [m, 0.0, 0.0, 0.0]).collect();
    let m_tex = Texture::new(g, w, h, TexelFormat::Rgba32F, Filter::Nearest, Some(&rgba)).unwrap();
    let target = Texture::new(g, w, h, TexelFormat::Rgba32F, Filter::Nearest, None).unwrap();

    let (mut worst_sinhc, mut worst_m, mut worst_inverse): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (scheme, sigma0) in [
        (Scheme::Matched, 1.0),
        (Scheme::Matched, 1.7),
        (Scheme::Invariant, 1.0),
        (Scheme::Euler, 1.0),
    ] {
        let matched = scheme == Scheme::Matched;
        let program = Program::new(
            g,
            &header(g, matched, false),
            ("diffuse.frag (probe)", &probe),
            &["u_rate", "u_f", "u_law"],
            &[],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let schedule = Schedule::new(scheme, sigma0, 20.0, 0.25).unwrap();
        let law: OffsetLaw = schedule.offset_law();
        for k in [0, 1, schedule.steps / 2, schedule.steps - 1] {
            let out = gl.draw(
                &program,
                &[("u_rate", &rate_tex), ("u_f", &m_tex)],
                law.uniform(k),
                &target,
            );
            for (i, texel) in out.iter().enumerate() {
                let rate = f64::from(rates[i]);
                let case = format!("{scheme} σ0 = {sigma0}, k = {k}, ρ = {rate}");
                // sinh(ρ)/ρ ∈ [1, 1.0105]: Horner's four products and sums, ½ ULP each,
                // and the constants' rounding: within 2 ULPs of the exact value (the
                // series' own truncation, 5e-11, is far below).
                let e = (f64::from(texel[0]) - sinhc(rate)).abs();
                worst_sinhc = worst_sinhc.max(e / ULP);
                assert!(
                    e <= 2.0 * ULP,
                    "sinhc at {case}: {} off by {e:.2e}",
                    texel[0]
                );

                // The offset, compared through the moment it gives (m⁻¹ is exact in f64):
                // m = t²·sinh(ρ)/ρ (matched) or t² (t = scale·e^(c_k ρ)). Budget: exp
                // (3 + 2|c_k ρ| ULP) twice (t is squared), the scale product, t·t, the
                // series (2 ULP), its product, m⁻¹'s subtraction and its division (2.5
                // ULP): 2(3 + 2|x|) + 10 ULPs. (Euler's t = 1·e^0 is exact.)
                let x = (law.step_coefficient(k) * rate).abs();
                let want_h = law.offset(rate, k);
                let want = if matched {
                    bilinear_moment(want_h)
                } else {
                    want_h * want_h
                };
                let got_h = f64::from(texel[1]);
                let got = if matched {
                    bilinear_moment(got_h)
                } else {
                    got_h * got_h
                };
                let e = (got - want).abs() / want;
                worst_m = worst_m.max(e / ULP);
                let budget = (2.0 * (3.0 + 2.0 * x) + 10.0) * ULP;
                assert!(
                    e <= budget,
                    "offset at {case}: h = {got_h} (moment {got}) vs {want_h} ({want}): \
                     {e:.2e} > {budget:.2e}"
                );

                // m⁻¹ on its own: the bilinear moment of the shader's offset is the moment
                // it was given, to the subtraction, the division (2.5 ULP) and the sum.
                let m = f64::from(moments[i]);
                let back = bilinear_moment(f64::from(texel[2]));
                let e = (back - m).abs();
                worst_inverse = worst_inverse.max(e / (m.max(1.0) * ULP));
                assert!(
                    e <= 6.0 * ULP * m.max(1.0),
                    "offset_for_moment({m}) = {} (moment {back})",
                    texel[2]
                );
            }
        }
    }
    eprintln!(
        "largest errors in f32 ULPs (2^-23 relative): sinhc {worst_sinhc:.2} (bound 2), offset \
         as its moment {worst_m:.2} (bound 16 to 28), offset_for_moment {worst_inverse:.2} \
         (bound 6)"
    );
}

/// One whole diffusion pass of the real shader. F(x, y) = a·(x − x0)² (independent of y)
/// and a rate constant along each row: at the column x0 the update is exactly
/// F(x0) + ρ·(F(x0 + h) + F(x0 − h) − 2F(x0)) = 2aρ·m(h), m the bilinear moment (the
/// hardware interpolates the parabola linearly between texels; the y neighbours add
/// nothing). So the pass's output there measures the offset it used, per rate and step,
/// in both layouts: ρ in a texture of its own, or in F's alpha (the offset layout).
#[test]
fn one_diffusion_pass_blurs_by_the_f64_schedules_moment() {
    let gl = Gl::open();
    let g = gl.gl();
    // 64 columns (a power of two: the shader's texture coordinates (x + ½)/64 and h/64 are
    // exact, only their sums round), x0 = 32; offsets stay below 31 px. One rate per row.
    let (w, h) = (64usize, 32usize);
    let x0 = 32usize;
    let a = 1.0 / 64.0;
    let rates: Vec<f32> = (0..h)
        .map(|j| (0.25 * (j + 1) as f64 / h as f64) as f32)
        .collect();
    let f_data: Vec<f32> = (0..h)
        .flat_map(|_| {
            (0..w).flat_map(move |x| {
                let d = x as f64 - x0 as f64;
                [(a * d * d) as f32, 0.0, 0.0, 1.0]
            })
        })
        .collect();
    let rate_data: Vec<f32> = (0..h).flat_map(|j| vec![rates[j]; w]).collect();
    let f_tex = Texture::new(g, w, h, TexelFormat::Rgba32F, Filter::Linear, Some(&f_data)).unwrap();
    let rate_tex =
        Texture::new(g, w, h, TexelFormat::R32F, Filter::Linear, Some(&rate_data)).unwrap();
    // The offset layout: the same F with each row's rate in alpha.
    let offset_data: Vec<f32> = f_data
        .chunks(4)
        .zip(&rate_data)
        .flat_map(|(f, &rate)| [f[0], f[1], f[2], rate])
        .collect();
    let offset_tex = Texture::new(
        g,
        w,
        h,
        TexelFormat::Rgba32F,
        Filter::Linear,
        Some(&offset_data),
    )
    .unwrap();
    let target = Texture::new(g, w, h, TexelFormat::Rgba32F, Filter::Nearest, None).unwrap();

    let mut worst: f64 = 0.0;
    let mut checked = 0;
    let cases = [
        (Scheme::Matched, 1.0),
        (Scheme::Matched, 1.7),
        (Scheme::Invariant, 1.0),
        (Scheme::Euler, 1.0),
    ];
    for ((scheme, sigma0), offset) in cases.into_iter().flat_map(|c| [(c, false), (c, true)]) {
        let matched = scheme == Scheme::Matched;
        let (uniforms, textures): (&[&str], Vec<(&str, &Texture)>) = if offset {
            (&["u_f", "u_law", "u_texel"], vec![("u_f", &offset_tex)])
        } else {
            (
                &["u_f", "u_rate", "u_law", "u_texel"],
                vec![("u_f", &f_tex), ("u_rate", &rate_tex)],
            )
        };
        let program = Program::new(
            g,
            &header(g, matched, offset),
            ("diffuse.frag", DIFFUSE),
            uniforms,
            &[],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let schedule = Schedule::new(scheme, sigma0, 20.0, 0.25).unwrap();
        let law = schedule.offset_law();
        let ks: Vec<u32> = if scheme == Scheme::Euler {
            vec![0]
        } else {
            (0..schedule.steps).collect()
        };
        for k in ks {
            let out = gl.draw(&program, &textures, law.uniform(k), &target);
            for (j, &rate) in rates.iter().enumerate() {
                let rate = f64::from(rate);
                let want_h = law.offset(rate, k);
                assert!(
                    want_h + 1.0 < (w - 1 - x0) as f64,
                    "offset {want_h} too large"
                );
                let want = bilinear_moment(want_h);
                let got = f64::from(out[j * w + x0][0]) / (2.0 * a * rate);
                let case = format!("{scheme} σ0 = {sigma0}, k = {k}, ρ = {rate}, offset {offset}");
                // Budget: the offset law as in the test above (16 + 4|c_k ρ| ULPs of m);
                // each neighbour's coordinate x0 + ½ ± h rounds to half an ULP of a value
                // below 1 times 64 texels, 2⁻¹⁹ texel, where the interpolated parabola has
                // slope a(2i + 1): (2i + 1)·2⁻¹⁹ of m for both; then the interpolation, the
                // weighted sums and the division above, 6 ULPs.
                let x = (law.step_coefficient(k) * rate).abs();
                let i = want_h.floor();
                let budget =
                    (2.0 * (3.0 + 2.0 * x) + 10.0 + 6.0) * ULP * want + (2.0 * i + 1.0) / 524_288.0;
                let e = (got - want).abs();
                worst = worst.max(e / budget);
                checked += 1;
                assert!(
                    e <= budget,
                    "{case}: the pass added 2aρ·{got} (h = {}), the schedule says 2aρ·{want} \
                     (h = {want_h}): {e:.2e} > {budget:.2e}",
                    brume::schedule::offset_for_moment(got)
                );
            }
        }
    }
    eprintln!("{checked} pixels; largest error {worst:.3} of its budget");
}
