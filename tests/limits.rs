//! Bounded work and clear limits: values that would cost hours or terabytes are refused up
//! front, naming the option, the limit and why; memory that runs out is said plainly; a
//! calib.txt at fault is named as the culprit.
use crate::common;

use brume::raster::Grid;
use brume::{gpu, Blur, Haze, Precision, Scheme, UniformBlur};
use common::*;
use std::path::Path;
use std::process::{Command, Output};

fn brume(dir: &Path, args: &[&str]) -> Output {
    let _lock = gl_lock();
    Command::new(env!("CARGO_BIN_EXE_brume"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run brume")
}

fn assert_refused(o: &Output, mentions: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("brume: error: "), "{err}");
    for m in mentions {
        assert!(err.contains(m), "should mention {m:?}: {err}");
    }
}

#[test]
fn a_tiny_rho_max_is_refused_not_run_for_hours() {
    let dir = tempfile::tempdir().unwrap();
    for rho in ["1e-9", "1e-5"] {
        let o = brume(dir.path(), &["render", "--rho-max", rho, "--out", "x.png"]);
        assert_refused(&o, &["--rho-max", "20000 diffusion steps"]);
    }
    assert!(!dir.path().join("x.png").exists());
}

#[test]
fn euler_beyond_the_step_limit_suggests_matched() {
    let blur = Blur {
        scheme: Scheme::Euler,
        ..Blur::default()
    };
    let err = blur.schedule(400.0, "sigma").unwrap_err().to_string();
    assert!(err.contains("invalid sigma = 400"), "{err}");
    assert!(err.contains("matched"), "{err}");
    // The paper's own Euler experiment is well inside the limit.
    assert_eq!(blur.schedule(25.0, "sigma").unwrap().steps, 1248);
    // A library user may raise the limit.
    let patient = Blur {
        max_steps: 400_000,
        ..blur
    };
    assert!(patient.schedule(400.0, "sigma").is_ok());
}

#[test]
fn accuracy_sigmas_are_bounded_before_any_allocation() {
    let dir = tempfile::tempdir().unwrap();
    for sigma in ["1500", "1e5", "1e6"] {
        let o = brume(dir.path(), &["bench", "accuracy", "--sigmas", sigma]);
        assert_refused(&o, &["--sigmas", "≤ 100 px"]);
    }
}

#[test]
fn huge_sky_factor_and_margin_are_named_as_given() {
    let dir = tempfile::tempdir().unwrap();
    let depth = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/aloe/disparity.png");
    let depth = depth.to_str().unwrap();
    let o = brume(
        dir.path(),
        &[
            "prep",
            "--depth",
            depth,
            "--out",
            "r.pfm",
            "--sky-factor",
            "1e308",
        ],
    );
    assert_refused(&o, &["--sky-factor = 1e308", "(1, 1000]"]);
    let o = brume(
        dir.path(),
        &[
            "prep", "--depth", depth, "--out", "r.pfm", "--margin", "1e39",
        ],
    );
    assert_refused(&o, &["--margin = 1e39"]);
}

/// A calib.txt whose doffs puts every point behind the camera is the calib's fault.
#[test]
fn negative_doffs_names_the_calib_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut pfm = b"Pf\n4 2\n-1\n".to_vec();
    for _ in 0..8 {
        pfm.extend_from_slice(&10f32.to_le_bytes());
    }
    std::fs::write(dir.path().join("disp0.pfm"), pfm).unwrap();
    std::fs::write(
        dir.path().join("calib.txt"),
        "cam0=[100 0 2; 0 100 1; 0 0 1]\ncam1=[100 0 2; 0 100 1; 0 0 1]\ndoffs=-50\n\
         baseline=100\nwidth=4\nheight=2\nndisp=10\nisint=0\nvmin=1\nvmax=10\n",
    )
    .unwrap();
    let o = brume(
        dir.path(),
        &[
            "prep",
            "--depth",
            "disp0.pfm",
            "--calib",
            "calib.txt",
            "--out",
            "r.pfm",
        ],
    );
    assert_refused(&o, &["calib.txt: doffs = -50"]);
}

/// `brume args` run in `dir` with its address space limited to `kib` KiB (`ulimit -v`),
/// as on a machine with that much memory left.
fn brume_within(dir: &Path, kib: u64, args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {kib} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_brume"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

/// The path of `name` among the large flat test images, as a string for an argument.
fn big(name: &str) -> String {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/big");
    data.join(name).display().to_string()
}

/// An image too large for the memory left is refused from its header, before it is
/// decoded, with the size, what it needs, and what to do; the old error was
/// "glGetError = 0x0505" after gigabytes had been allocated. An EXR or a PFM too: their
/// headers went unread, and the render aborted on a failed allocation after decoding.
#[test]
fn an_image_too_large_for_memory_is_refused_with_sizes() {
    let dir = tempfile::tempdir().unwrap();
    // The header of an 8000x6000 colour PFM and one pixel: refused from the header before
    // the decoder would find the data short.
    let pfm = dir.path().join("flat-8000x6000.pfm");
    let mut bytes = b"PF\n8000 6000\n-1.0\n".to_vec();
    bytes.extend_from_slice(&[0; 12]);
    std::fs::write(&pfm, bytes).unwrap();
    let images = [
        big("flat-8000x6000.png"),
        big("flat-8000x6000-y.exr"),
        pfm.display().to_string(),
    ];
    let depth = big("flat-8000x6000-depth16.png");
    for image in &images {
        let args = [
            "render",
            "--image",
            image,
            "--depth",
            &depth,
            "--depth-format",
            "kitti",
        ];
        let args = [&args[..], &["--no-prep", "--out", "out.png"]].concat();
        let _lock = gl_lock();
        let o = brume_within(dir.path(), 3_000_000, &args);
        assert_refused(&o, &["out of memory", "8000x6000", "GB", "smaller image"]);
        assert!(!dir.path().join("out.png").exists());
    }
}

/// A depth map whose pre-processing cannot fit in the memory left is refused before its
/// maps are allocated, where `brume prep` of an 8000x6000 map under `ulimit -v 700000`
/// aborted the process on a failed allocation.
#[test]
fn a_depth_map_too_large_to_pre_process_is_refused_with_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let depth = big("flat-8000x6000-depth16.png");
    // Room to decode the map (672 MB from about 770 left), not to pre-process it.
    let mentions = [
        "out of memory",
        "pre-processing",
        "8000x6000",
        "smaller depth map",
    ];
    assert_prep_refused(
        dir.path(),
        900_000,
        &depth,
        ["--depth-format", "kitti"],
        &mentions,
    );
}

/// Runs `brume prep` of `depth`, read as `format` (a flag and its value) says with a 45°
/// field of view, under `kib` KiB of address space, and asserts that it is refused naming
/// `mentions` and writes no output.
fn assert_prep_refused(dir: &Path, kib: u64, depth: &str, format: [&str; 2], mentions: &[&str]) {
    let args = [
        "prep",
        "--depth",
        depth,
        format[0],
        format[1],
        "--fov",
        "45",
        "--out",
        "range.pfm",
    ];
    assert_refused(&brume_within(dir, kib, &args), mentions);
    assert!(!dir.join("range.pfm").exists());
}

/// A depth map whose decoding cannot fit in the memory left is refused from its header, in
/// every format whose header gives its size, before the decoder allocates: `brume prep` of
/// an 8000x6000 EXR or 16-bit PNG under `ulimit -v 400000` aborted the process on a failed
/// allocation (the PFM and `.npy` here, a header and four bytes, were "truncated"; the
/// float64 TIFF, over the `tiff` crate's default limit, "decoder limits exceeded").
#[test]
fn a_depth_map_too_large_to_decode_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let pfm = dir.path().join("flat-8000x6000.pfm");
    std::fs::write(&pfm, [&b"Pf\n8000 6000\n-1.0\n"[..], &[0; 4]].concat()).unwrap();
    let npy = dir.path().join("flat-8000x6000.npy");
    let mut header = b"{'descr': '<f4', 'fortran_order': False, 'shape': (6000, 8000), }".to_vec();
    header.resize(117, b' ');
    header.push(b'\n');
    let npy_bytes = [&b"\x93NUMPY\x01\x00\x76\x00"[..], &header, &[0; 4]].concat();
    std::fs::write(&npy, npy_bytes).unwrap();
    let maps = [
        (big("flat-8000x6000-depth16.png"), "8000x6000"),
        (big("flat-8000x6000-y.exr"), "8000x6000"),
        (big("flat-5800x5800-f64.tif"), "5800x5800"),
        (pfm.display().to_string(), "8000x6000"),
        (npy.display().to_string(), "8000x6000"),
    ];
    for (map, size) in &maps {
        let mentions = [
            "out of memory",
            "reading the depth map",
            map,
            size,
            "smaller depth map",
        ];
        let scale = ["--depth-scale", "0.001"];
        assert_prep_refused(dir.path(), 400_000, map, scale, &mentions);
    }
}

/// A depth map a file holds is refused from its own header before it is inflated or
/// decoded: an `.npz` member (a compressed member of one repeated value is a few hundred
/// kilobytes for gigabytes of array: `brume prep` of a 559 kB `np.savez_compressed`
/// 8000x6000 float64 map was killed under a 300-500 MB cgroup limit) and a phone JPEG's
/// depth image (here `dd8.jpg`'s Dynamic Depth PNG, its header saying 8000x6000).
#[test]
fn a_depth_map_inside_a_file_is_refused_from_its_own_header() {
    let dir = tempfile::tempdir().unwrap();
    let npy = npy_bytes("<f8", "(6000, 8000)", false, &[0; 8]);
    let npz = dir.path().join("pro.npz");
    std::fs::write(&npz, npz_bytes(&[("depth", npy)], true)).unwrap();
    let jpeg = dir.path().join("portrait.jpg");
    std::fs::write(&jpeg, with_depth_png_sized(8000, 6000)).unwrap();
    let maps = [
        (npz.display().to_string(), "pro.npz (its array 'depth')"),
        (
            jpeg.display().to_string(),
            "portrait.jpg (its Dynamic Depth",
        ),
    ];
    for (map, named) in &maps {
        let mentions = ["out of memory", named, "8000x6000", "smaller depth map"];
        let auto = ["--depth-format", "auto"];
        assert_prep_refused(dir.path(), 400_000, map, auto, &mentions);
    }
}

/// `dd8.jpg` (a Dynamic Depth JPEG whose depth PNG is appended last) with that PNG's
/// header saying `width` x `height`, its checksum mended; the pixels stay 32x24's.
fn with_depth_png_sized(width: u32, height: u32) -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gdepth/dd8.jpg");
    let mut bytes = std::fs::read(path).unwrap();
    let ihdr = bytes.windows(4).rposition(|w| w == b"IHDR").unwrap();
    bytes[ihdr + 4..ihdr + 8].copy_from_slice(&width.to_be_bytes());
    bytes[ihdr + 8..ihdr + 12].copy_from_slice(&height.to_be_bytes());
    let crc = crc32fast::hash(&bytes[ihdr..ihdr + 17]);
    bytes[ihdr + 17..ihdr + 21].copy_from_slice(&crc.to_be_bytes());
    bytes
}

/// The textures a renderer keeps between frames are what its memory check leaves out (a
/// batch's second frame was refused the 168 MB a 2048x1024 frame's textures take, which
/// the first had left in place), and `free_kept_textures` frees them, to be made again by
/// the next frame (as a batch does before it tries a frame refused memory alone).
#[test]
fn kept_textures_are_counted_and_freed() {
    let (_lock, mut headless) = renderer();
    let r = headless.renderer().unwrap();
    let (w, h) = (64, 48);
    let image = noise_image(w, h, 3);
    let range = ramp_range(w, h);
    let blur = Blur {
        coarse_from: None,
        ..Blur::default()
    };
    let render = |r: &mut brume::Renderer| {
        r.render(&image, &range, &Haze::default(), &blur).unwrap();
    };
    assert_eq!(r.kept_texture_bytes(), 0);
    render(r);
    // The image (RGB32F) and the range (R32F) uploaded, and haze's two RGBA32F targets
    // (its airlight is the same everywhere: one target holds τ·(E − L∞) and ρ).
    assert_eq!(r.kept_texture_bytes(), (12 + 4 + 2 * 16) * (w * h) as u64);
    let live = brume::gpu::live_objects();
    r.free_kept_textures();
    assert_eq!(r.kept_texture_bytes(), 0);
    assert!(brume::gpu::live_objects() < live);
    render(r);
    assert_eq!(brume::gpu::live_objects(), live);
}

/// A batch's frame refused memory is tried again alone once the other frames are done,
/// and refused a second time is one failure: the 8000x6000 photo here cannot be held in
/// the memory left at all, the small frame beside it is written. (Under a 450 MB cgroup
/// limit, two of three 2048x1024 frames failed, refused memory while the loader held the
/// next frame; tried alone, every one is written.)
#[test]
fn a_frame_refused_memory_is_tried_again_alone() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64, 48);
    save_png(
        &dir.path().join("small.png").display().to_string(),
        w,
        h,
        &vec![[90, 120, 150]; w * h],
    );
    let depth = vec![2560u16; w * h]; // 10 m as KITTI stores it
    let bytes: Vec<u8> = depth.iter().flat_map(|v| v.to_ne_bytes()).collect();
    let small_depth = dir.path().join("small-depth.png");
    image::save_buffer(
        &small_depth,
        &bytes,
        w as u32,
        h as u32,
        image::ColorType::L16,
    )
    .unwrap();
    let manifest = format!(
        "image,depth\nsmall.png,small-depth.png\n{},{}\n",
        big("flat-8000x6000.png"),
        big("flat-8000x6000-depth16.png")
    );
    std::fs::write(dir.path().join("frames.csv"), manifest).unwrap();
    let args = [
        "batch",
        "--manifest",
        "frames.csv",
        "--depth-format",
        "kitti",
        "--fov",
        "60",
        "--beta",
        "0.02",
        "--out",
        "foggy",
    ];
    let o = {
        let _lock = gl_lock();
        brume_within(dir.path(), 3_000_000, &args)
    };
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("flat-8000x6000.png") && err.contains("tried again alone"),
        "{err}"
    );
    assert!(
        err.contains("1 frames and 0 outputs failed (1 outputs written)"),
        "{err}"
    );
    let log = std::fs::read_to_string(dir.path().join("foggy/brume-batch-1-of-1.jsonl")).unwrap();
    let statuses: Vec<&str> = log
        .lines()
        .map(|l| {
            if l.contains("\"status\":\"ok\"") {
                "ok"
            } else {
                "failed"
            }
        })
        .collect();
    assert_eq!(statuses, ["ok", "failed"], "{log}");
    assert!(
        log.contains("out of memory") && log.contains("8000x6000"),
        "{log}"
    );
}

/// A file too large to hold in the memory left is refused with its size and what can be
/// had, where the error said only "a.pfm: out of memory".
#[test]
fn a_file_too_large_to_read_says_how_large() {
    let dir = tempfile::tempdir().unwrap();
    // An 8000x6000 colour PFM of zeros, sparse: 576 MB long, nothing on disk.
    let pfm = dir.path().join("a.pfm");
    let header = b"PF\n8000 6000\n-1.0\n";
    std::fs::write(&pfm, header).unwrap();
    let file = std::fs::OpenOptions::new().write(true).open(&pfm).unwrap();
    file.set_len(header.len() as u64 + 8000 * 6000 * 12)
        .unwrap();
    let o = brume_within(dir.path(), 400_000, &["compare", "a.pfm", "a.pfm"]);
    let mentions = ["out of memory", "reading a.pfm", "576 MB", "smaller file"];
    assert_refused(&o, &mentions);
}

/// A sky photo whose turbidity estimation cannot fit in the memory left is refused from
/// its header, before it is decoded: a 4096x4096 EXR sky under `ulimit -v 1000000`
/// aborted the process on a failed allocation.
#[test]
fn a_sky_photo_too_large_for_memory_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let sky = big("flat-8000x6000-y.exr");
    let args = [
        "turbidity",
        &sky,
        "--sun-zenith",
        "40",
        "--sun-azimuth",
        "0",
    ];
    let o = brume_within(dir.path(), 2_000_000, &args);
    let mentions = ["out of memory", "turbidity", "8000x6000", "smaller image"];
    assert_refused(&o, &mentions);
}

/// Two images whose comparison cannot fit in the memory left are refused from their
/// headers, before either is decoded: `brume compare` of two 8000x6000 photos took 7.5 GB
/// (the SSIM's moments for the whole image; 1.4 GB now) and aborted the process on a
/// failed allocation under `ulimit -v 1000000`.
#[test]
fn images_too_large_to_compare_are_refused_from_their_headers() {
    let dir = tempfile::tempdir().unwrap();
    let image = big("flat-8000x6000.png");
    let o = brume_within(dir.path(), 1_000_000, &["compare", &image, &image]);
    assert_refused(&o, &["out of memory", "comparing", "GB", "smaller images"]);
}

/// `bench speed` and `bench refine` at a `--size` whose image and textures cannot fit in
/// the memory left are refused before they allocate them, naming the option: both
/// aborted the process on a failed allocation of the 8000x6000 image under `ulimit -v
/// 1000000`.
#[test]
fn image_benchmarks_too_large_for_memory_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for bench in ["speed", "refine"] {
        let _lock = gl_lock();
        let args = ["bench", bench, "--size", "8000x6000", "--runs", "1"];
        let o = brume_within(dir.path(), 1_000_000, &args);
        assert_refused(&o, &["out of memory", "--size 8000x6000", "smaller --size"]);
    }
}

/// The per-pixel estimate the memory check uses follows the textures the pipeline makes:
/// two colour targets for a medium of uniform in-scattered light (ρ in their alpha, any
/// τ), and the rate and a chromatic τ's pair on top for the others.
#[test]
fn bytes_per_pixel_follow_precision_layout_and_chromatic_tau() {
    use brume::Pipeline;
    let tinted = Haze {
        tint: [0.8, 1.0, 1.3],
        ..Haze::default()
    };
    assert_eq!(
        Pipeline::bytes_per_pixel(Precision::F32, &Haze::default()),
        2 * 16
    );
    assert_eq!(Pipeline::bytes_per_pixel(Precision::F16, &tinted), 2 * 8);
    let grey = premultiplied(Haze::default());
    assert_eq!(Pipeline::bytes_per_pixel(Precision::F32, &grey), 2 * 16 + 4);
    assert_eq!(Pipeline::bytes_per_pixel(Precision::F16, &grey), 2 * 8 + 2);
    assert_eq!(
        Pipeline::bytes_per_pixel(Precision::F32, &premultiplied(tinted)),
        2 * 16 + 4 + 2 * 8
    );
    // And a render leaves no object behind but what the pipeline keeps.
    let (_lock, mut r) = renderer();
    let image = noise_image(16, 12, 1);
    let range = Grid::filled(16, 12, 0.5f32);
    r.render(&image, &range, &Haze::default(), &Blur::default())
        .unwrap();
    let kept = gpu::live_objects();
    for _ in 0..3 {
        r.render(&image, &range, &UniformBlur::new(2.0), &Blur::default())
            .unwrap();
    }
    r.render(&image, &range, &Haze::default(), &Blur::default())
        .unwrap();
    // Two more programs (the uniform blur's medium and composite passes), nothing else.
    assert_eq!(gpu::live_objects(), kept + 2);
}
