use brume::haze::RenderSpec;
use brume::raster::Grid;
use brume::{Precision, Renderer, Scheme};
fn main() {
    let (w, h) = (1600, 1120);
    let img = Grid::from_fn(w, h, |x, y| {
        [((x * 7 + y * 3) % 256) as f32 / 255.0, 0.5, 0.25]
    });
    let range = Grid::filled(w, h, 0.5f32);
    let mut r = Renderer::new(None).unwrap();
    println!("{}", r.caps().renderer);
    for (scheme, prec) in [
        (Scheme::Matched, Precision::F32),
        (Scheme::Matched, Precision::F16),
        (Scheme::Invariant, Precision::F32),
    ] {
        let spec = RenderSpec::uniform(25.0, 1.0, scheme, prec);
        let mut t = vec![];
        for _ in 0..4 {
            let out = r.render(&img, &range, &spec).unwrap();
            t.push(out.times.total_ms);
            println!(
                "{scheme} {prec} {:?} total {:.1} passes {:?}",
                out.times.clock,
                out.times.total_ms,
                out.times
                    .pass_ms
                    .iter()
                    .map(|v| (v * 10.0).round() / 10.0)
                    .collect::<Vec<_>>()
            );
        }
    }
}
