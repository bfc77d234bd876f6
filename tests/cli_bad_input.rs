//! Hostile input through the `brume` binary: every case must fail with the right exit code
//! (1 for a bad value or file, 2 for a malformed command line), name the file or option
//! on stderr, and leave the directory exactly as it was: pre-existing outputs byte for
//! byte, inputs untouched, no new file and no leftover temporary. Unix only: the cases
//! reach inputs through symbolic links.
#![cfg(unix)]

use crate::common;

use brume::io::output::{write_rgba, write_scalar};
use brume::raster::Grid;
use common::snapshot;
use std::fs;
use std::process::Command;
use std::sync::Mutex;

/// The binary may open a GL context; llvmpipe uses every core, so run one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

/// What every pre-existing output holds before a case runs.
const PRECIOUS: &[u8] = b"precious bytes that no failed command may touch\n";

/// One command line and what its failure must look like.
struct Case {
    args: Vec<String>,
    code: i32,
    mentions: Vec<String>,
}

/// `base` then `extra` (each split at spaces: no file name here has one), failing with
/// `code` and naming every word of `mentions`.
fn case(base: &str, extra: &str, code: i32, mentions: &str) -> Case {
    let words = |s: &str| s.split_whitespace().map(String::from).collect::<Vec<_>>();
    Case {
        args: words(base).into_iter().chain(words(extra)).collect(),
        code,
        mentions: words(mentions),
    }
}

/// A directory of small inputs, good and bad, and outputs that already exist.
fn fixtures() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let colour = |w, h| Grid::from_fn(w, h, |x, y| [x as f32 / 24.0, y as f32 / 16.0, 0.5, 1.0]);
    write_rgba(&p("im.png"), &colour(24, 16)).unwrap();
    write_rgba(&p("small.png"), &colour(20, 16)).unwrap();
    write_scalar(
        &p("range.pfm"),
        &Grid::from_fn(24, 16, |x, _| 1.0 + x as f32),
    )
    .unwrap();
    write_scalar(&p("small.pfm"), &Grid::filled(20, 16, 2.0f32)).unwrap();
    let jpeg =
        image::RgbImage::from_fn(24, 16, |x, y| image::Rgb([x as u8 * 10, y as u8 * 15, 128]));
    jpeg.save(p("im.jpg")).unwrap();
    let d16 = image::ImageBuffer::<image::Luma<u16>, _>::from_fn(24, 16, |x, _| {
        image::Luma([1000 + x as u16])
    });
    d16.save(p("d16.png")).unwrap();
    let d8 = image::GrayImage::from_fn(24, 16, |x, _| image::Luma([10 + x as u8]));
    d8.save(p("d8.png")).unwrap();

    let truncate = |from: &str, to: &str| {
        let bytes = fs::read(p(from)).unwrap();
        fs::write(p(to), &bytes[..bytes.len() / 2]).unwrap();
    };
    truncate("im.png", "trunc.png");
    truncate("im.jpg", "trunc.jpg");
    truncate("range.pfm", "trunc.pfm");
    fs::write(p("corrupt.png"), b"this is not a PNG at all").unwrap();
    fs::write(p("corrupt.jpg"), b"\xff\xd8\xff\xe0 not a JPEG either").unwrap();
    fs::write(p("corrupt.pfm"), b"PF\n24 sixteen\n-1\n").unwrap();
    fs::write(
        p("calib_bad.txt"),
        "cam0=[3997.684 0 11.7; 0 3997.684 8.1; 0 0 1]\ncam1=[3997.684 0 13.0; 0 3997.684 8.1; 0 0 1]\n\
         doffs=abc\nbaseline=193.001\nwidth=24\nheight=16\nndisp=290\n",
    )
    .unwrap();
    fs::write(p("calib_short.txt"), "width=24\nheight=16\n").unwrap();

    for out in [
        "out.png",
        "out.pfm",
        "out.exr",
        "vis.png",
        "table.csv",
        "fig.svg",
        "fig.png",
    ] {
        fs::write(p(out), PRECIOUS).unwrap();
    }
    round_two_fixtures(dir.path());
    fs::create_dir(p("adir.png")).unwrap();
    fs::create_dir(p("sub")).unwrap();
    fs::write(p("afile"), b"a file, not a folder").unwrap();
    std::os::unix::fs::symlink("im.png", p("link.png")).unwrap();
    std::os::unix::fs::symlink("out.pfm", p("outlink.png")).unwrap();
    fs::hard_link(p("im.png"), p("hard.png")).unwrap();
    fs::hard_link(p("table.csv"), p("table-hard.svg")).unwrap();
    dir
}

/// Runs every case in a fresh fixture directory and reports all the failures at once.
fn run_matrix(cases: &[Case]) {
    let dir = fixtures();
    let before = snapshot(dir.path());
    let mut failures = Vec::new();
    for c in cases {
        let o = {
            let _lock = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
            Command::new(env!("CARGO_BIN_EXE_brume"))
                .args(&c.args)
                .current_dir(dir.path())
                .output()
                .expect("run brume")
        };
        let err = String::from_utf8_lossy(&o.stderr);
        let mut wrong = Vec::new();
        if o.status.code() != Some(c.code) {
            wrong.push(format!("exit {:?}, expected {}", o.status.code(), c.code));
        }
        for m in &c.mentions {
            if !err.contains(m.as_str()) {
                wrong.push(format!("stderr does not name {m:?}"));
            }
        }
        if err.contains("panicked") {
            wrong.push("panicked".into());
        }
        if c.code == 1 && !err.starts_with("brume: error: ") {
            wrong.push("stderr is not one `brume: error:` line".into());
        }
        let after = snapshot(dir.path());
        if after != before {
            let changed: Vec<&String> = before
                .keys()
                .chain(after.keys())
                .filter(|k| before.get(*k) != after.get(*k))
                .collect();
            wrong.push(format!("directory changed: {changed:?}"));
            // Put the fixtures back so that the next case starts clean.
            for k in after.keys().filter(|k| !before.contains_key(*k)) {
                let path = dir.path().join(k);
                let _ = fs::remove_file(&path).or_else(|_| fs::remove_dir_all(&path));
            }
            for (k, v) in &before {
                let path = dir.path().join(k);
                if after.get(k) != Some(v) && fs::metadata(&path).is_ok_and(|m| m.is_file()) {
                    fs::write(&path, v).unwrap();
                }
            }
        }
        if !wrong.is_empty() {
            failures.push(format!(
                "brume {}\n    {}\n    stderr: {}",
                c.args.join(" "),
                wrong.join("; "),
                err.trim_end()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

const RENDER: &str = "render --image im.png --depth range.pfm --depth-kind range";

#[test]
fn render_refuses_bad_files() {
    let r = |args: &str, mentions: &str| case("render --out out.png", args, 1, mentions);
    let range = "--depth-kind range";
    run_matrix(&[
        r(
            &format!("--image nope.png --depth range.pfm {range}"),
            "nope.png",
        ),
        r(
            &format!("--image corrupt.png --depth range.pfm {range}"),
            "corrupt.png",
        ),
        r(
            &format!("--image trunc.png --depth range.pfm {range}"),
            "trunc.png",
        ),
        r(
            &format!("--image corrupt.jpg --depth range.pfm {range}"),
            "corrupt.jpg",
        ),
        r(
            &format!("--image trunc.jpg --depth range.pfm {range}"),
            "trunc.jpg",
        ),
        r(
            &format!("--image im.png --depth nope.pfm {range}"),
            "nope.pfm",
        ),
        r(
            &format!("--image im.png --depth corrupt.pfm {range}"),
            "corrupt.pfm",
        ),
        r(
            &format!("--image im.png --depth trunc.pfm {range}"),
            "trunc.pfm",
        ),
        r(
            &format!("--image im.png --depth small.pfm {range}"),
            "im.png small.pfm 24x16 20x16",
        ),
        r(
            &format!("--image small.png --depth range.pfm {range}"),
            "small.png range.pfm",
        ),
        r("--image im.jpg --depth corrupt.png", "corrupt.png"),
        r(
            "--image im.png --depth range.pfm --calib calib_bad.txt",
            "calib_bad.txt doffs",
        ),
        r(
            "--image im.png --depth range.pfm --calib calib_short.txt",
            "calib_short.txt",
        ),
        r(
            "--image im.png --depth range.pfm --calib nope.txt",
            "nope.txt",
        ),
        r("--depth range.pfm", "--image"),
        case("render --image im.png --out out.png", "", 1, "--depth"),
    ]);
}

#[test]
fn render_refuses_bad_outputs() {
    let out = |path: &str, mentions: &str| case(RENDER, &format!("--out {path}"), 1, mentions);
    run_matrix(&[
        out("im.png", "--out im.png"),
        out("range.pfm", "--out range.pfm"),
        out("./sub/../im.png", "--out"),
        out("link.png", "--out link.png"),
        out("hard.png", "--out hard.png"),
        out("out.bmp", "--out out.bmp .png"),
        out("out", "--out"),
        out("nodir/out.png", "--out nodir"),
        out("afile/out.png", "--out afile"),
        out("adir.png", "--out adir.png"),
        case("render", "--out demo.gif", 1, "--out demo.gif"),
    ]);
}

#[test]
fn render_names_every_bad_number() {
    let bad = |flag_value: &str, code| {
        let flag = flag_value.split_whitespace().next().unwrap();
        case(RENDER, &format!("--out out.png {flag_value}"), code, flag)
    };
    let from = |depth: &str, flag_value: &str| {
        let flag = flag_value.split_whitespace().last().unwrap();
        let base = format!("render --image im.png --out out.png --depth {depth}");
        case(&base, flag_value, 1, flag)
    };
    run_matrix(&[
        bad("--ka -1", 1),
        bad("--ka -inf", 1),
        bad("--ks nan", 1),
        bad("--lambda -3", 1),
        bad("--sigma0 -1", 1),
        bad("--sigma0 0", 1),
        bad("--rho-max 0.3", 1),
        bad("--rho-max -0.1", 1),
        bad("--uniform-sigma -2", 1),
        bad("--margin -1", 1),
        bad("--sky-factor 0.5", 1),
        bad("--sky-factor -2", 1),
        bad("--sky-min-area -0.1", 1),
        bad("--sky-min-area 2", 1),
        bad("--seed -1", 1),
        bad("--ka abc", 2),
        bad("--seed 1.5", 2),
        bad("--airlight -1,0,0", 2),
        bad("--airlight 1,2", 2),
        bad("--tint -1,1,1", 2),
        bad("--tint 0,1,1", 2),
        bad("--scheme fast", 2),
        bad("--precision f64", 2),
        bad("--depth-format bmp", 2),
        bad("--depth-kind height", 2),
        bad("--egl nowhere", 2),
        bad("--frobnicate 1", 2),
        from("d16.png", "--depth-format png16 --depth-scale -1"),
        from("d16.png", "--depth-format png16 --depth-scale 0"),
        from("d8.png", "--depth-format middlebury2006 --baseline -5"),
        from("d8.png", "--depth-format middlebury2006 --focal -1"),
        from(
            "d8.png",
            "--depth-format middlebury2006 --disparity-offset -inf",
        ),
    ]);
}

#[test]
fn prep_is_all_or_nothing() {
    let p = |args: &str, mentions: &str| {
        case(
            "prep --depth range.pfm --depth-kind range",
            args,
            1,
            mentions,
        )
    };
    run_matrix(&[
        // The colour image is read before anything is written.
        p("--image corrupt.png --out out.pfm", "corrupt.png"),
        p("--image nope.png --out out.pfm --vis vis.png", "nope.png"),
        p(
            "--image small.png --out out.pfm --vis vis.png",
            "small.png 20x16",
        ),
        p("--image trunc.jpg --out out.exr", "trunc.jpg"),
        // A picture that cannot be written leaves the range map alone.
        p("--out out.pfm --vis adir.png", "adir.png"),
        p("--out out.pfm --vis nodir/vis.png", "--vis nodir"),
        // --vis is a PNG.
        p("--out out.pfm --vis out.pfm", "--vis out.pfm .png"),
        p("--out out.pfm --vis vis.pfm", "--vis vis.pfm .png"),
        p("--out out.pfm --vis vis.exr", "--vis vis.exr .png"),
        p("--out out.pfm --vis vis", "--vis"),
        // Outputs that are inputs, or each other.
        p("--out range.pfm", "--out range.pfm"),
        p("--out out.pfm --image im.png --vis im.png", "--vis im.png"),
        p(
            "--out out.pfm --image im.png --vis link.png",
            "--vis link.png",
        ),
        p(
            "--out out.pfm --image im.png --vis hard.png",
            "--vis hard.png",
        ),
        p("--out out.pfm --vis outlink.png", "--vis outlink.png --out"),
        p("--out out.png", "--out out.png .pfm"),
        p("--out afile/out.pfm", "--out afile"),
        // Bad numbers and files.
        p("--out out.pfm --seed -1", "--seed"),
        p("--out out.pfm --sky-min-area -1", "--sky-min-area"),
        p("--out out.pfm --margin -2", "--margin"),
        case("prep --depth nope.pfm --out out.pfm", "", 1, "nope.pfm"),
        case("prep --depth trunc.pfm --out out.pfm", "", 1, "trunc.pfm"),
        case("prep --out out.pfm", "", 1, "--depth"),
        case("prep --depth range.pfm", "", 2, "--out"),
    ]);
}

#[test]
fn bench_is_all_or_nothing() {
    let few = "--sigmas 2 --schemes matched --precisions f32";
    let accuracy = format!("bench accuracy --image im.png {few}");
    let speed = format!("bench speed {few}");
    let a = |args: &str, mentions: &str| case(&accuracy, args, 1, mentions);
    let s = |args: &str, code, mentions: &str| case(&speed, args, code, mentions);
    run_matrix(&[
        // Outputs that are the input, or each other.
        a("--csv im.png", "--csv im.png"),
        a("--plot im.png", "--plot im.png"),
        a("--csv link.png", "--csv link.png"),
        a("--plot hard.png", "--plot hard.png"),
        a("--csv fig.svg --plot fig.svg", "--plot fig.svg --csv"),
        a("--csv new.svg --plot ./new.svg", "--plot --csv"),
        a("--csv table.csv --plot table-hard.svg", "--plot --csv"),
        // A plot that cannot be written leaves the CSV alone.
        a("--csv table.csv --plot adir.png", "adir.png"),
        a("--csv table.csv --plot fig.jpg", "--plot fig.jpg"),
        a("--csv table.csv --plot nodir/fig.svg", "--plot nodir"),
        a("--plot fig.svg --csv afile/t.csv", "--csv afile"),
        a("--csv adir.png", "adir.png"),
        // Bad inputs and numbers.
        case(
            "bench accuracy --image corrupt.png --csv table.csv",
            "",
            1,
            "corrupt.png",
        ),
        case(
            "bench accuracy --image nope.png --csv table.csv",
            "",
            1,
            "nope.png",
        ),
        a("--sigmas -1", "--sigmas"),
        a("--sigmas -1,2", "--sigmas"),
        a("--sigmas 0.5", "--sigmas"),
        a("--sigmas 2,x", "--sigmas"),
        a("--schemes fast", "--schemes"),
        a("--precisions f64", "--precisions"),
        s("--size -1x3 --csv table.csv", 1, "--size"),
        s("--size 0x3", 1, "--size"),
        s("--runs -1", 1, "--runs"),
        s("--runs 0", 1, "--runs"),
        s("--max-passes -5", 1, "--max-passes"),
        s("--runs two", 2, "--runs"),
        s("--tau blue", 2, "--tau"),
        s("--coarse-from 1", 2, "`off` or a scale in px ≥ 2"),
        case(
            &accuracy,
            "--coarse-from NaN",
            2,
            "'NaN' for '--coarse-from",
        ),
        s("--csv range.pfm.csv --plot table.csv", 1, "--plot"),
        case("bench sideways", "", 2, "sideways"),
    ]);
}

#[test]
fn info_refuses_bad_options() {
    run_matrix(&[
        case("info --bogus", "", 2, "--bogus"),
        case("info --egl nowhere", "", 2, "--egl"),
        case("info extra", "", 2, "extra"),
        case("frobnicate", "", 2, "frobnicate"),
        // A command with no headless context (CPU only) has no EGL display to choose.
        case(
            "sun --latitude 48 --longitude 2 --time 2024-06-21T12:00:00Z",
            "--egl device",
            1,
            "--egl device CPU",
        ),
    ]);
}

/// Cityscapes' camera file of the fixture frame.
const CAMERA_JSON: &str = r#"{"extrinsic": {"baseline": 0.2}, "intrinsic": {"fx": 2000.0, "fy": 2000.0, "u0": 12.0, "v0": 8.0}}"#;

/// The inputs of the second hostile-input sweep: a one-frame Cityscapes dataset `cs/`,
/// manifests whose rows climb out of `--out` or land on one output, an output folder
/// `bout/` with a link out of it, a sky mask that is all sky and an image too small for
/// SSIM.
fn round_two_fixtures(dir: &std::path::Path) {
    let p = |name: &str| dir.join(name);
    let frame = "x_000000_000019";
    for (kind, file) in [
        ("leftImg8bit", format!("{frame}_leftImg8bit.png")),
        ("disparity", format!("{frame}_disparity.png")),
        ("camera", format!("{frame}_camera.json")),
    ] {
        let folder = p(&format!("cs/{kind}/train/x"));
        fs::create_dir_all(&folder).unwrap();
        let path = folder.join(file);
        match kind {
            "leftImg8bit" => {
                image::RgbImage::from_fn(24, 16, |x, y| {
                    image::Rgb([x as u8 * 9, y as u8 * 12, 90])
                })
                .save(path)
                .unwrap();
            }
            "disparity" => image::ImageBuffer::<image::Luma<u16>, _>::from_fn(24, 16, |x, _| {
                image::Luma([2000 + 40 * x as u16])
            })
            .save(path)
            .unwrap(),
            _ => fs::write(path, CAMERA_JSON).unwrap(),
        }
    }
    fs::create_dir_all(p("man")).unwrap();
    let manifest = |name: &str, rows: &[&str]| {
        let text = std::iter::once("image,depth").chain(rows.iter().copied());
        fs::write(p(name), text.collect::<Vec<_>>().join("\n") + "\n").unwrap();
    };
    manifest("man/climb.csv", &["../im.png,../d16.png"]);
    manifest("man/climb2.csv", &["sub/../../im.png,../d16.png"]);
    manifest("twice.csv", &["im.png,d16.png", "im.png,d16.png"]);
    manifest("pngjpg.csv", &["im.png,d16.png", "im.jpg,d16.png"]);
    manifest("header.csv", &[]);
    fs::create_dir_all(p("bout")).unwrap();
    std::os::unix::fs::symlink("../man", p("bout/leftImg8bit")).unwrap();
    image::GrayImage::from_pixel(24, 16, image::Luma([255]))
        .save(p("allsky.png"))
        .unwrap();
    image::RgbImage::from_pixel(8, 8, image::Rgb([90, 40, 10]))
        .save(p("tiny.png"))
        .unwrap();
    for (name, key, value) in [
        (
            "cam_baseline.json",
            "\"baseline\": 0.2",
            "\"baseline\": 1e300",
        ),
        ("cam_fx.json", "\"fx\": 2000.0", "\"fx\": 1e-300"),
        ("cam_u0.json", "\"u0\": 12.0", "\"u0\": 1e12"),
    ] {
        fs::write(p(name), CAMERA_JSON.replace(key, value)).unwrap();
    }
}

/// Issue 18, data loss: `view`'s outputs are checked like every other command's before a
/// window is asked for (so with or without a display): not an input, also through a
/// link, the extension its format.
#[test]
fn view_never_writes_over_an_input() {
    let photo = "render --image im.png --depth range.pfm --depth-kind range";
    let v = |args: &str, mentions: &str| case("view --frames 1", args, 1, mentions);
    run_matrix(&[
        v(
            &format!("--screenshot im.png {photo}"),
            "--screenshot im.png",
        ),
        v(
            &format!("--screenshot link.png {photo}"),
            "--screenshot link.png im.png",
        ),
        v(
            &format!("--screenshot hard.png {photo}"),
            "--screenshot hard.png",
        ),
        v(
            &format!("--stats range.pfm {photo}"),
            "--stats range.pfm .json",
        ),
        v("--screenshot shot.jpg", "--screenshot shot.jpg .png"),
        v("--screenshot adir.png", "--screenshot adir.png"),
        v("--stats nodir/s.json", "--stats nodir"),
        v("--window 100000x100000", "--window 8192"),
        v("--window 0x0", "--window"),
        case("view --frames 100000", "", 1, "--frames 10000"),
        v("render --ka -1", "--ka"),
        v("scene --size 100000x2", "--size"),
    ]);
}

/// Issue 18, escapes and collisions: every output of a batch lies under `--out` and is
/// one frame's, proven before anything (even `--out`) is made.
#[test]
fn batch_outputs_stay_under_out_and_apart() {
    let b = |args: &str, mentions: &str| case("batch --out bo", args, 1, mentions);
    run_matrix(&[
        b("--manifest man/climb.csv", "im.png climbs"),
        b("--manifest man/climb2.csv", "im.png climbs"),
        b("--manifest twice.csv", "im.png twice"),
        b("--manifest pngjpg.csv", "im.jpg im.png"),
        b("--manifest header.csv", "header.csv"),
        b("cs cs", "x_000000_000019_leftImg8bit.png twice"),
        case("batch --out bout", "cs", 1, "--out bout man"),
        case("batch --out afile", "cs", 1, "--out afile"),
    ]);
}

/// Issue 18, validation: a batch checks every option before it makes `--out` or its log,
/// and names the flag, not the library's field.
#[test]
fn batch_checks_every_option_first() {
    let b = |args: &str, mentions: &str| case("batch cs --out bo", args, 1, mentions);
    run_matrix(&[
        b("--sky-factor 1", "--sky-factor"),
        b("--margin -1", "--margin"),
        b("--seed -1", "--seed"),
        b("--far-outlier-factor 0.5", "--far-outlier-factor"),
        b("--scheme euler --lambda 1000", "--lambda"),
        b("--sky-mask nope.png", "--sky-mask nope.png"),
        b("--sky-mask small.png", "--sky-mask small.png 20x16 24x16"),
        b("--beta 1e-300", "--beta 1e-300"),
        b("--beta 0.01,nan", "--beta nan"),
        b("--no-prep --margin 3", "--margin --no-prep"),
        b("--shard 0/4", "--shard"),
        b("--shard slurm", "--shard SLURM_ARRAY_TASK_ID"),
        // Options that cannot take effect.
        b(
            "--compat foggy-cityscapes --lambda 3",
            "--lambda 3 --compat foggy-cityscapes",
        ),
        b(
            "--compat foggy-cityscapes --precision f16",
            "--precision f16 --compat",
        ),
        b(
            "--refine none --refine-eps 0.01",
            "--refine-eps --refine none",
        ),
        b("--no-sky --sky-factor 2", "--sky-factor --no-sky"),
    ]);
}

/// Issue 18, caps: every size and count has an upper bound, said up front.
#[test]
fn sizes_and_counts_are_capped() {
    let sky = "sky --turbidity 3 --sun-zenith 30 --sun-azimuth 0 --out out.png";
    run_matrix(&[
        case(sky, "--size 20000", 1, "--size 16384"),
        case("bench turbidity", "--size 100000", 1, "--size 2048"),
        case(
            "bench turbidity",
            "--estimations 1000000000000",
            1,
            "--estimations 10000",
        ),
        case(
            "bench turbidity",
            "--samples 1000000",
            1,
            "--samples 100000",
        ),
        case(
            "bench turbidity",
            "--estimations 10000 --samples 1000",
            1,
            "--estimations sample",
        ),
        case("bench fog", "--runs 1000000", 1, "--runs 1000"),
        case("bench speed", "--runs 5000", 1, "--runs 1000"),
        case("bench speed", "--size 100000x100000", 1, "--size"),
        case(
            "turbidity im.png",
            "--repeats 1000000000000",
            1,
            "--repeats 10000",
        ),
        case("turbidity im.png", "--samples 1000000", 1, "--samples"),
        case(
            "turbidity im.png",
            "--repeats 10000 --samples 10000",
            1,
            "--repeats sample",
        ),
        case(
            "scene --out out.png",
            "--frames 100000",
            1,
            "--frames 10000",
        ),
        case("scene --out out.png", "--size 20000x10", 1, "--size"),
    ]);
}

/// Issue 18, memory: a size inside the documented range that the memory left cannot hold
/// is refused before the allocation (it used to abort), for `sky` and `scene` as for
/// `render`.
#[test]
fn sizes_that_do_not_fit_in_memory_are_refused() {
    let dir = fixtures();
    let before = snapshot(dir.path());
    let bin = env!("CARGO_BIN_EXE_brume");
    for args in [
        "sky --turbidity 3 --sun-zenith 30 --sun-azimuth 0 --size 16384 --out big.png",
        "scene --size 8192x8192 --out big.png",
    ] {
        let o = {
            let _lock = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
            Command::new("sh")
                .arg("-c")
                .arg(format!("ulimit -v 2000000; exec {bin} {args}"))
                .current_dir(dir.path())
                .output()
                .unwrap()
        };
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args}: {err}");
        assert!(
            err.starts_with("brume: error: out of memory: --size") && err.contains("can be had"),
            "{args}: {err}"
        );
        assert_eq!(snapshot(dir.path()), before, "{args}");
    }
}

/// Issue 18: options of the other medium, aerial values out of range or named after
/// another command's flag, aerial perspective on a range with no metric scale or no field
/// of view, options that cannot take effect.
#[test]
fn render_refuses_options_that_cannot_take_effect() {
    let r =
        |args: &str, mentions: &str| case(RENDER, &format!("--out out.png {args}"), 1, mentions);
    let aerial = "--medium aerial --turbidity 3 --metres-per-unit 1 --fov 40";
    run_matrix(&[
        r(
            "--sky nope.png --turbidity 99 --metres-per-unit -5",
            "--turbidity --medium aerial",
        ),
        r("--pitch 3", "--pitch --medium aerial"),
        r("--horizon-zenith 80", "--horizon-zenith --medium aerial"),
        r(&format!("{aerial} --ks 2"), "--ks --medium haze"),
        r(&format!("{aerial} --tint 1,1,2"), "--tint --medium haze"),
        r(
            &format!("{aerial} --uniform-sigma 3"),
            "--uniform-sigma --medium haze",
        ),
        r(
            "--uniform-sigma 3 --airlight 1,1,1",
            "--airlight --uniform-sigma",
        ),
        r("--uniform-sigma 3 --ks 0.5", "--ks --uniform-sigma"),
        r(
            "--beta 0.01 --compat foggy-cityscapes --scheme euler",
            "--scheme euler --compat foggy-cityscapes",
        ),
        r("--refine-radius 5", "--refine-radius --refine"),
        r(
            "--refine none --refine-radius 5",
            "--refine-radius --refine none",
        ),
        r(
            "--medium aerial --turbidity 1000 --metres-per-unit 1 --fov 40",
            "--turbidity 1000 [1, 20]",
        ),
        r(
            &format!("{aerial} --from-turbidity 1000"),
            "--from-turbidity 1000",
        ),
        r(&format!("{aerial} --from-turbidity 0"), "--from-turbidity"),
        r(
            &format!("{aerial} --horizon-zenith 200"),
            "--horizon-zenith 200",
        ),
        r(&format!("{aerial} --horizon-zenith -5"), "--horizon-zenith"),
        r(
            &format!("{aerial} --horizon-zenith NaN"),
            "--horizon-zenith NaN",
        ),
        r(&format!("{aerial} --altitude -1e9"), "--altitude"),
        r(&format!("{aerial} --pitch 90"), "--pitch 90"),
        r(&format!("{aerial} --horizon-row 1e9"), "--horizon-row 1e9"),
        r(
            "--medium aerial --turbidity 3 --fov 40",
            "--metres-per-unit range.pfm",
        ),
        r("--medium aerial --turbidity 3 --metres-per-unit 1", "--fov"),
        r("--near 1 --far 10", "--near zbuffer"),
        r("--reversed-z", "--reversed-z zbuffer"),
        case(
            "render --image im.png --depth range.pfm --out out.png",
            "--depth-kind affine --near 1 --far 9 --reversed-z",
            1,
            "--reversed-z zbuffer",
        ),
        case(
            "render --image im.png --depth range.pfm --out out.png",
            "--depth-kind affine --far 10",
            1,
            "--near affine street",
        ),
        r("--sky-beyond 0", "--sky-beyond 0 positive inf"),
        case(
            "render --image im.png --depth range.pfm --out out.png",
            "--depth-kind zbuffer --near 1 --far 0.5 --fov 40",
            1,
            "--far 0.5 inf",
        ),
        r("--right im.png", "--right im.png disparity range.pfm"),
        r("--no-prep --sky-mask allsky.png", "--sky-mask --no-prep"),
        r("--sky-mask allsky.png", "--sky-mask allsky.png sky"),
        case(
            RENDER,
            "--out out.png --fov 40 --focal 500",
            2,
            "--fov --focal",
        ),
        case("compare tiny.png tiny.png", "", 1, "tiny.png 8x8 11x11"),
        case(
            "prep --depth range.pfm --depth-kind range --out r.pfm",
            "--near 1",
            1,
            "--near",
        ),
    ]);
}

/// Issue 18: a camera file with an absurd value is refused naming the file and the key
/// (it used to pass, and fail later as "no valid range value", naming neither).
#[test]
fn absurd_camera_files_are_named() {
    let r = "render --image im.png --depth d16.png --depth-format cityscapes --out out.png";
    run_matrix(&[
        case(
            r,
            "--camera cam_baseline.json",
            1,
            "cam_baseline.json baseline 1e300",
        ),
        case(r, "--camera cam_fx.json", 1, "cam_fx.json fx"),
        case(r, "--camera cam_u0.json", 1, "cam_u0.json u0"),
    ]);
}
