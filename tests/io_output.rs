//! Output writers: formats, row order, atomicity, errors.

use std::path::Path;

use brume::io::depth::{read_pfm, Pfm};
use brume::io::image::{linear_to_srgb, load_linear_rgb, srgb_to_linear};
use brume::io::output::{same_file, write_bytes, write_png_rgb8, write_rgba, write_scalar};
use brume::raster::{Grid, RgbaImage};
use brume::Error;

/// 3x2 image whose top row differs from the bottom row.
fn sample() -> RgbaImage {
    Grid::from_fn(3, 2, |x, y| {
        let v = srgb_to_linear((x * 60 + y * 100) as f32 / 255.0);
        [v, 1.0 - v, if y == 0 { 1.0 } else { 0.0 }, 0.5]
    })
}

fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn png_round_trip_is_8bit_srgb() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("o.png");
    let img = sample();
    write_rgba(&path, &img).unwrap();
    let raw = image::open(&path).unwrap();
    assert_eq!(raw.color(), image::ColorType::Rgb8);
    let raw = raw.to_rgb8();
    assert_eq!(raw.get_pixel(1, 1).0[0], 160);
    assert_eq!(raw.get_pixel(0, 0).0[2], 255);
    let back = load_linear_rgb(&path).unwrap();
    for (a, b) in img.as_slice().iter().zip(back.as_slice()) {
        for c in 0..3 {
            // Within half an 8-bit step, measured in the encoded domain.
            let step = (linear_to_srgb(a[c]) - linear_to_srgb(b[c])).abs() * 255.0;
            assert!(step <= 0.5 + 1e-3, "{a:?} vs {b:?}");
        }
    }
    assert_eq!(entries(dir.path()), ["o.png"]);
}

#[test]
fn png_clamps_out_of_range_and_nan() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.PNG");
    let img = Grid::from_vec(2, 1, vec![[-1.0, 2.0, f32::NAN, 1.0], [0.5, 0.0, 1.0, 0.0]]);
    write_rgba(&path, &img).unwrap();
    let raw = image::open(&path).unwrap().to_rgb8();
    assert_eq!(raw.get_pixel(0, 0).0, [0, 255, 0]);
    assert_eq!(raw.get_pixel(1, 0).0, [188, 0, 255]);
}

#[test]
fn pfm_rgb_is_linear_little_endian_bottom_to_top() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("o.pfm");
    let img = sample();
    write_rgba(&path, &img).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let header = b"PF\n3 2\n-1.0\n";
    assert!(bytes.starts_with(header));
    // The first pixel in the file is the bottom-left one.
    let first: Vec<f32> = bytes[header.len()..header.len() + 12]
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(first, img.get(0, 1)[..3]);
    match read_pfm(&path).unwrap() {
        Pfm::Rgb(back) => {
            let want: Vec<[f32; 3]> = img.as_slice().iter().map(|p| [p[0], p[1], p[2]]).collect();
            assert_eq!(back.as_slice(), &want[..]);
        }
        Pfm::Grey(_) => panic!("expected PF"),
    }
}

#[test]
fn exr_rgba_reads_back_equal() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("o.exr");
    let img = sample();
    write_rgba(&path, &img).unwrap();
    let back = read_first_flat_layer_from_file(&path).unwrap();
    let layer = back.layer_data;
    assert_eq!((layer.size.width(), layer.size.height()), (3, 2));
    for (c, name) in ["R", "G", "B", "A"].iter().enumerate() {
        let ch = layer
            .channel_data
            .list
            .iter()
            .find(|ch| ch.name.to_string() == *name)
            .unwrap_or_else(|| panic!("channel {name}"));
        let FlatSamples::F32(values) = &ch.sample_data else {
            panic!("{name} is not f32")
        };
        let want: Vec<f32> = img.as_slice().iter().map(|p| p[c]).collect();
        assert_eq!(values, &want, "{name}");
    }
}

#[test]
fn scalar_exr_has_one_y_channel() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.exr");
    let map = Grid::from_fn(4, 3, |x, y| (x + 10 * y) as f32);
    write_scalar(&path, &map).unwrap();
    let back = read_first_flat_layer_from_file(&path).unwrap().layer_data;
    assert_eq!(back.channel_data.list.len(), 1);
    assert_eq!(back.channel_data.list[0].name.to_string(), "Y");
    let FlatSamples::F32(values) = &back.channel_data.list[0].sample_data else {
        panic!("not f32")
    };
    assert_eq!(values, map.as_slice());
    // And the depth loader reads it back.
    let d = brume::io::depth::read_exr_scalar(&path).unwrap();
    assert_eq!(d, map);
}

/// A map of many tiles, written several times (its tiles compressed in parallel): the
/// same bytes each time, the tiles in increasing order as the header says.
#[test]
fn an_exr_is_the_same_bytes_each_time() {
    use exr::meta::attribute::LineOrder;
    let dir = tempfile::tempdir().unwrap();
    // 64 x 64 tiles: 48 of them; values that do not compress alike.
    let map = Grid::from_fn(512, 384, |x, y| {
        ((x * 7919 + y * 104_729) % 1000) as f32 * 0.37
    });
    let bytes: Vec<Vec<u8>> = (0..4)
        .map(|i| {
            let path = dir.path().join(format!("r{i}.exr"));
            write_scalar(&path, &map).unwrap();
            std::fs::read(&path).unwrap()
        })
        .collect();
    assert!(bytes.iter().all(|b| b == &bytes[0]), "the files differ");
    let meta =
        exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(&bytes[0]), false).unwrap();
    assert_eq!(meta.headers[0].line_order, LineOrder::Increasing);
    assert_eq!(
        brume::io::depth::read_exr_scalar(&dir.path().join("r0.exr")).unwrap(),
        map
    );
}

#[test]
fn unknown_extension_is_an_error_and_creates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["o.gif", "o", "o.tiff"] {
        let err = write_rgba(&dir.path().join(name), &sample()).unwrap_err();
        assert!(matches!(err, Error::InvalidParameter { .. }), "{err}");
        assert!(
            err.to_string().contains(".png, .jpg, .jpeg, .pfm or .exr"),
            "{err}"
        );
    }
    let err = write_scalar(&dir.path().join("r.png"), &Grid::filled(1, 1, 1.0)).unwrap_err();
    assert!(err.to_string().contains(".pfm or .exr"), "{err}");
    assert!(entries(dir.path()).is_empty());
}

// A rename replaces its destination whatever the destination's mode, so a file its owner
// made read-only to keep it was replaced by `--out` like any other.
#[test]
fn a_read_only_file_is_not_replaced() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let kept = dir.path().join("kept.png");
    std::fs::write(&kept, b"the user's").unwrap();
    std::fs::set_permissions(&kept, std::fs::Permissions::from_mode(0o444)).unwrap();
    let err = write_rgba(&kept, &sample()).unwrap_err().to_string();
    assert!(
        err.contains("kept.png") && err.contains("read-only"),
        "{err}"
    );
    let err = brume::io::output::check_image_output(&kept, "--out").unwrap_err();
    assert!(err.to_string().contains("--out"), "{err}");
    assert_eq!(std::fs::read(&kept).unwrap(), b"the user's");
    assert_eq!(entries(dir.path()), ["kept.png"], "no temporary left");

    let image = dir.path().join("im.png");
    ::image::RgbImage::from_pixel(8, 6, ::image::Rgb([90, 120, 150]))
        .save(&image)
        .unwrap();
    ::image::GrayImage::from_pixel(8, 6, ::image::Luma([100]))
        .save(dir.path().join("d.png"))
        .unwrap();
    let args = [
        "render", "--image", "im.png", "--depth", "d.png", "--out", "kept.png",
    ];
    let run = crate::common::brume(dir.path(), &args);
    let err = crate::common::stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("--out") && err.contains("read-only"), "{err}");
    assert_eq!(std::fs::read(&kept).unwrap(), b"the user's");

    std::fs::set_permissions(&kept, std::fs::Permissions::from_mode(0o644)).unwrap();
    write_rgba(&kept, &sample()).unwrap();
}

/// A link named as the output is kept and its file replaced, through a chain of
/// relative and absolute links, into another folder, and where it leads to no file
/// yet; a link to an existing file counts as present for `write_bytes_unless_present`.
#[test]
fn an_output_through_a_link_replaces_its_file_and_keeps_the_link() {
    use std::os::unix::fs::symlink;
    let dir = tempfile::tempdir().unwrap();
    let (d, other) = (dir.path(), dir.path().join("other"));
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("file.png"), b"old").unwrap();
    symlink("other/file.png", d.join("near.png")).unwrap();
    symlink(d.join("near.png"), d.join("out.png")).unwrap();
    write_bytes(&d.join("out.png"), b"new").unwrap();
    assert_eq!(std::fs::read(other.join("file.png")).unwrap(), b"new");
    for link in ["out.png", "near.png"] {
        let meta = std::fs::symlink_metadata(d.join(link)).unwrap();
        assert!(meta.file_type().is_symlink(), "{link} was replaced");
    }
    assert!(!brume::io::output::write_bytes_unless_present(&d.join("out.png"), b"newer").unwrap());
    assert_eq!(std::fs::read(other.join("file.png")).unwrap(), b"new");

    symlink("other/later.png", d.join("dangling.png")).unwrap();
    write_bytes(&d.join("dangling.png"), b"made").unwrap();
    assert_eq!(std::fs::read(other.join("later.png")).unwrap(), b"made");
    assert!(std::fs::symlink_metadata(d.join("dangling.png"))
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(
        entries(&other),
        ["file.png", "later.png"],
        "a temporary left"
    );
}

/// A named pipe is written into (a reader gets the whole output) and stays a pipe; a
/// link to a device (`/dev/null`) leaves the device as it is; no temporary is left.
#[test]
fn a_named_pipe_or_a_device_is_written_into_not_replaced() {
    use std::io::Read;
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let pipe = dir.path().join("pipe.png");
    let c_path = std::ffi::CString::new(pipe.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo reads nothing else.
    assert_eq!(unsafe { libc::mkfifo(c_path.as_ptr(), 0o600) }, 0);
    let reader = {
        let pipe = pipe.clone();
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            std::fs::File::open(pipe)
                .unwrap()
                .read_to_end(&mut bytes)
                .unwrap();
            bytes
        })
    };
    let output = vec![7u8; 200_000];
    write_bytes(&pipe, &output).unwrap();
    // Before the join: a reader of a replaced pipe would wait for a writer forever.
    let kind = std::fs::symlink_metadata(&pipe).unwrap().file_type();
    assert!(kind.is_fifo(), "the pipe was replaced");
    assert_eq!(reader.join().unwrap(), output);

    let mut names = vec!["pipe.png"];
    let null = Path::new("/dev/null");
    if std::fs::metadata(null).is_ok_and(|m| m.file_type().is_char_device()) {
        std::os::unix::fs::symlink(null, dir.path().join("null.png")).unwrap();
        write_bytes(&dir.path().join("null.png"), b"gone").unwrap();
        let kind = std::fs::metadata(null).unwrap().file_type();
        assert!(kind.is_char_device(), "/dev/null was replaced");
        names.insert(0, "null.png");
    }
    assert_eq!(entries(dir.path()), names, "a temporary left");
}

// `render --out` through a symbolic link used to replace the link with a file and leave
// the file it named as it was.
#[test]
fn render_through_a_link_writes_the_file_it_leads_to() {
    let dir = tempfile::tempdir().unwrap();
    ::image::RgbImage::from_pixel(8, 6, ::image::Rgb([90, 120, 150]))
        .save(dir.path().join("im.png"))
        .unwrap();
    ::image::GrayImage::from_pixel(8, 6, ::image::Luma([100]))
        .save(dir.path().join("d.png"))
        .unwrap();
    std::fs::create_dir(dir.path().join("results")).unwrap();
    std::fs::write(dir.path().join("results/fog.png"), b"last run's").unwrap();
    std::os::unix::fs::symlink("results/fog.png", dir.path().join("latest.png")).unwrap();
    let args = [
        "render",
        "--image",
        "im.png",
        "--depth",
        "d.png",
        "--out",
        "latest.png",
    ];
    let run = crate::common::brume(dir.path(), &args);
    assert!(run.status.success(), "{}", crate::common::stderr(&run));
    let link = std::fs::symlink_metadata(dir.path().join("latest.png")).unwrap();
    assert!(link.file_type().is_symlink(), "the link was replaced");
    let written = ::image::open(dir.path().join("results/fog.png")).unwrap();
    assert_eq!((written.width(), written.height()), (8, 6));
    assert_eq!(entries(&dir.path().join("results")), ["fog.png"]);
}

#[test]
fn failing_write_leaves_nothing_and_keeps_the_old_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/dir/o.png");
    let err = write_rgba(&missing, &sample()).unwrap_err();
    assert!(matches!(err, Error::Io { .. }), "{err}");
    // Named by the path given and its missing folder, not by the temporary file's name.
    let said = err.to_string();
    assert!(said.contains("o.png: its folder") && said.contains("dir does not exist"));
    assert!(!said.contains(".brume-"), "{said}");
    assert!(entries(dir.path()).is_empty());

    // A write that fails half-way (pixel count wrong) must not touch an existing file.
    let existing = dir.path().join("keep.png");
    std::fs::write(&existing, b"old").unwrap();
    assert!(write_png_rgb8(&existing, 2, 2, &[[0, 0, 0]; 3]).is_err());
    assert_eq!(std::fs::read(&existing).unwrap(), b"old");
    // Overwriting an existing file works and leaves no temporary behind.
    write_png_rgb8(&existing, 1, 1, &[[1, 2, 3]]).unwrap();
    assert_eq!(
        image::open(&existing).unwrap().to_rgb8().get_pixel(0, 0).0,
        [1, 2, 3]
    );
    assert_eq!(entries(dir.path()), ["keep.png"]);
}

#[test]
#[cfg(unix)]
fn output_is_not_private() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("o.pfm");
    write_scalar(&path, &Grid::filled(1, 1, 1.0)).unwrap();
    let mode = std::fs::metadata(&path).unwrap().permissions().mode();
    assert_ne!(
        mode & 0o044,
        0,
        "mode {mode:o}: others cannot read the output"
    );
}

#[test]
fn same_file_resolves_paths() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.png");
    std::fs::write(&a, b"x").unwrap();
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    assert!(same_file(&a, &sub.join("../a.png")));
    assert!(!same_file(&a, &dir.path().join("b.png")));
    assert!(!same_file(
        &dir.path().join("b.png"),
        &dir.path().join("b.png")
    ));
    #[cfg(unix)]
    {
        let link = dir.path().join("link.png");
        std::os::unix::fs::symlink(&a, &link).unwrap();
        assert!(same_file(&a, &link));
        let hard = dir.path().join("hard.png");
        std::fs::hard_link(&a, &hard).unwrap();
        assert!(same_file(&a, &hard));
    }
}

#[test]
fn byte_write_leaves_nothing_on_a_bad_directory() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("missing").join("out.csv");
    assert!(write_bytes(&bad, b"x").is_err());
    let good = dir.path().join("out.csv");
    write_bytes(&good, b"hello").unwrap();
    assert_eq!(std::fs::read(&good).unwrap(), b"hello");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn an_output_set_is_written_all_or_nothing() {
    use brume::io::output::Outputs;
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.pfm"));
    std::fs::write(&a, b"old a").unwrap();
    let range = Grid::filled(3, 2, 1.5f32);

    // A failure while staging the second file leaves the first destination alone and
    // removes the first temporary.
    let mut set = Outputs::new();
    set.stage_bytes(&a, b"new a").unwrap();
    assert!(set
        .stage_scalar(&dir.path().join("no/b.pfm"), &range)
        .is_err());
    drop(set);
    assert_eq!(entries(dir.path()), ["a.csv"]);
    assert_eq!(std::fs::read(&a).unwrap(), b"old a");

    // One file twice, even under another spelling, is refused.
    let mut set = Outputs::new();
    set.stage_bytes(&a, b"new a").unwrap();
    let again = dir.path().join(".").join("a.csv");
    let err = set.stage_bytes(&again, b"x").unwrap_err().to_string();
    assert!(err.contains("a.csv"), "{err}");
    drop(set);
    assert_eq!(entries(dir.path()), ["a.csv"]);

    // Nothing lands before commit; then everything does.
    let mut set = Outputs::new();
    set.stage_bytes(&a, b"new a").unwrap();
    set.stage_scalar(&b, &range).unwrap();
    assert_eq!(std::fs::read(&a).unwrap(), b"old a");
    assert!(!b.exists());
    set.commit().unwrap();
    assert_eq!(std::fs::read(&a).unwrap(), b"new a");
    assert!(matches!(read_pfm(&b).unwrap(), Pfm::Grey(_)));
    assert_eq!(entries(dir.path()), ["a.csv", "b.pfm"]);
}
