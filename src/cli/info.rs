//! `brume info`: what EGL and GL driver brume finds and what they can do.

use super::args::InfoArgs;
use brume::caps::Capabilities;
use brume::egl::Platform;
use brume::Result;

pub fn run(args: &InfoArgs, egl: Option<Platform>) -> Result<()> {
    let renderer = super::open_renderer(egl)?;
    let caps = renderer.caps();
    if args.json {
        let caps = serde_json::to_value(caps).expect("capabilities serialise");
        outln!(
            "{}",
            serde_json::to_string_pretty(&super::stamped(caps)).expect("JSON values serialise")
        );
    } else {
        print_text(caps);
    }
    Ok(())
}

fn print_text(c: &Capabilities) {
    let yes = |b: bool| if b { "yes" } else { "no" };
    outln!("brume {} (sources {})", brume::VERSION, brume::SOURCES);
    if let Some(egl) = &c.egl {
        outln!("EGL platform       {}", egl.platform);
        outln!("EGL vendor         {} (EGL {})", egl.vendor, egl.version);
    }
    outln!("GL vendor          {}", c.vendor);
    outln!("GL renderer        {}", c.renderer);
    outln!("GL version         {}", c.version);
    outln!("GLSL version       {}", c.shading_language_version);
    outln!("max texture size   {}", c.max_texture_size);
    outln!("EXT_color_buffer_float       {}", yes(c.color_buffer_float));
    outln!(
        "EXT_color_buffer_half_float  {}",
        yes(c.color_buffer_half_float)
    );
    outln!(
        "OES_texture_float_linear     {}",
        yes(c.texture_float_linear)
    );
    outln!(
        "EXT_disjoint_timer_query     {}",
        yes(c.disjoint_timer_query)
    );
    outln!(
        "OES_EGL_image_external_essl3 {}",
        yes(c.egl_image_external_essl3)
    );
    outln!("OES_EGL_image_external       {}", yes(c.egl_image_external));
    let f32_ok = c.require_precision(brume::Precision::F32).is_ok();
    let f16_ok = c.require_precision(brume::Precision::F16).is_ok();
    outln!(
        "precisions usable  f32: {}, f16: {}",
        yes(f32_ok),
        yes(f16_ok)
    );
    outln!(
        "timing clock       {}",
        if c.disjoint_timer_query {
            "gpu-timer (GL_TIME_ELAPSED)"
        } else {
            "wall (glFinish + monotonic clock)"
        }
    );
}
