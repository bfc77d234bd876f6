//! Writes the seed corpora of the fuzz targets in `fuzz/` (one folder per target):
//!
//! ```text
//! cargo run --example fuzz_seeds -- [OUT_DIR]
//! ```
//!
//! `OUT_DIR` defaults to `fuzz/seeds`. Every seed is a small valid file (a few pixels, a
//! crop of the Aloe disparity in `tests/data/aloe`) in each layout and encoding the
//! loaders accept, so that the fuzzer starts from inputs that reach deep into each
//! decoder instead of having to find a magic number first. The `depth_png` and
//! `load_range` seeds start with the option bytes that `fuzz/src/lib.rs` decodes; the
//! `sky_mask` seeds with one byte that picks the mask format, the `tables` seeds with one
//! byte that picks the table. The `camera`, `manifest` and `sun_time` seeds are plain
//! Cityscapes camera files, `brume batch` CSV manifests and RFC 3339 times.

use std::io::Cursor;
use std::path::{Path, PathBuf};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

fn main() -> Res<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("fuzz/seeds"));
    let aloe = image::open(root.join("tests/data/aloe/disparity.png"))?.to_luma8();
    let (cx, cy) = (aloe.width() / 2, aloe.height() / 2);
    let crop: Vec<u8> = image::imageops::crop_imm(&aloe, cx, cy, 12, 9)
        .to_image()
        .into_raw();
    let crop16: Vec<u16> = crop.iter().map(|&d| u16::from(d) * 40).collect();
    let floats: Vec<f32> = crop.iter().map(|&d| f32::from(d) / 4.0).collect();
    let small = [1.5f32, 0.0, f32::NAN, 2.0, 3.25, f32::INFINITY];

    let mut seeds = Seeds::new(&out);
    seeds.put("pfm", "grey_le.pfm", pfm("Pf", 12, 9, &floats, true, "\n"));
    seeds.put("pfm", "grey_be.pfm", pfm("Pf", 3, 2, &small, false, "\n"));
    seeds.put("pfm", "rgb.pfm", pfm("PF", 2, 1, &small, true, "\n"));
    seeds.put("pfm", "crlf.pfm", pfm("Pf", 3, 2, &small, true, "\r\n"));

    let calib = calib_txt(12, 9);
    seeds.put("calib", "calib.txt", calib.clone().into_bytes());
    seeds.put(
        "calib",
        "calib_dy.txt",
        format!("{calib}dyavg=0.5\ndymax=2\nunknown=1\n").into_bytes(),
    );

    let png8 = png(&crop, 12, 9, image::ExtendedColorType::L8)?;
    let png16 = png(&be16(&crop16), 12, 9, image::ExtendedColorType::L16)?;
    let png_la = png(
        &[9, 255, 0, 0, 30, 255],
        3,
        1,
        image::ExtendedColorType::La8,
    )?;
    let with = |a: u8, b: u8, file: &[u8]| [&[a, b][..], file].concat();
    // Option bytes: format in bits 0-2 of the first (0 auto, 2 middlebury2006, 3 kitti,
    // 4 nyu, 5 tum, 6 png16), kind in bits 3-4, flags for scale, focal and baseline in
    // bits 5-7; see `options` in fuzz/src/lib.rs.
    seeds.put("depth_png", "auto8.bin", with(0, 0, &png8));
    seeds.put("depth_png", "m2006_given.bin", with(2 | 0xC0, 1, &png8));
    seeds.put("depth_png", "kitti.bin", with(3, 0, &png16));
    seeds.put("depth_png", "nyu_range.bin", with(4 | 2 << 3, 0, &png16));
    seeds.put("depth_png", "tum_focal.bin", with(5 | 0x40, 0, &png16));
    seeds.put("depth_png", "png16.bin", with(6 | 0x20, 2, &png16));
    seeds.put(
        "depth_png",
        "png16_disp.bin",
        with(6 | 3 << 3 | 0xE0, 3, &png16),
    );
    seeds.put("depth_png", "grey_alpha.bin", with(2, 0, &png_la));

    use exr::prelude::{Compression, FlatSamples};
    let f16s = FlatSamples::F16(small.iter().map(|&v| half::f16::from_f32(v)).collect());
    let u32s = FlatSamples::U32(vec![1, 0, 7, 9, 2, 4]);
    let z = || FlatSamples::F32(small.to_vec());
    let exrs = [
        (
            "z_plain.exr",
            vec![("Z", z())],
            Compression::Uncompressed,
            false,
        ),
        (
            "y_zip.exr",
            vec![("Y", f16s.clone())],
            Compression::ZIP16,
            false,
        ),
        (
            "gz_rle.exr",
            vec![("G", f16s), ("Z", z())],
            Compression::RLE,
            false,
        ),
        ("r_piz.exr", vec![("R", z())], Compression::PIZ, false),
        (
            "depth_u32.exr",
            vec![("depth", u32s)],
            Compression::ZIP1,
            false,
        ),
        (
            "z_tiled.exr",
            vec![("Z", z())],
            Compression::Uncompressed,
            true,
        ),
    ];
    for (name, channels, compression, tiled) in exrs {
        seeds.put("exr", name, exr(channels, compression, tiled)?);
    }
    // The other decompressors. exr stores a block raw when compressing does not make it
    // smaller, which it never does at 3x2: these are 32x32 smooth ramps, whose blocks are
    // compressed, so that the seeds reach B44's, PXR24's and DWA's decoders (a B44 block
    // made the colour decoder panic before exr was built without overflow checks; a DWAA
    // block claiming 1.7 PB aborted brume before `io::codec::exr::check_dwa_blocks`).
    for (name, compression) in [
        ("b44", Compression::B44),
        ("b44a", Compression::B44A),
        ("pxr24", Compression::PXR24),
        ("dwaa", Compression::DWAA(None)),
        ("dwab", Compression::DWAB(None)),
    ] {
        let halves = || FlatSamples::F16(ramp(32).map(half::f16::from_f32).collect());
        let floats = || FlatSamples::F32(ramp(32).collect());
        let depth = vec![("Z", floats())];
        seeds.put(
            "exr",
            &format!("z_{name}.exr"),
            exr_sized(depth, compression, 32)?,
        );
        let rgb = vec![("R", halves()), ("G", halves()), ("B", halves())];
        seeds.put(
            "colour_image",
            &format!("rgb_{name}.exr"),
            exr_sized(rgb, compression, 32)?,
        );
    }

    use tiff::encoder::{colortype, Compression as Tc, DeflateLevel};
    let f64s: Vec<f64> = small.iter().map(|&v| f64::from(v)).collect();
    let tiffs = [
        (
            "f32.tif",
            tiff(|e| e.write_image::<colortype::Gray32Float>(12, 9, &floats))?,
        ),
        (
            "f64.tif",
            tiff(|e| e.write_image::<colortype::Gray64Float>(3, 2, &f64s))?,
        ),
        (
            "f32_lzw.tif",
            tiff_with(Tc::Lzw, |e| {
                e.write_image::<colortype::Gray32Float>(12, 9, &floats)
            })?,
        ),
        (
            "f32_deflate.tif",
            tiff_with(Tc::Deflate(DeflateLevel::default()), |e| {
                e.write_image::<colortype::Gray32Float>(3, 2, &small)
            })?,
        ),
        (
            "u16.tif",
            tiff(|e| e.write_image::<colortype::Gray16>(3, 1, &[1, 2, 3]))?,
        ),
    ];
    for (name, bytes) in tiffs {
        seeds.put("tiff", name, bytes);
    }

    let le32: Vec<u8> = small.iter().flat_map(|v| v.to_le_bytes()).collect();
    let be32: Vec<u8> = small.iter().flat_map(|v| v.to_be_bytes()).collect();
    let le64: Vec<u8> = small
        .iter()
        .flat_map(|v| f64::from(*v).to_le_bytes())
        .collect();
    seeds.put("npy", "f4.npy", npy(1, "<f4", "(2, 3)", false, &le32));
    seeds.put(
        "npy",
        "f8_fortran.npy",
        npy(1, "<f8", "(3, 2)", true, &le64),
    );
    seeds.put(
        "npy",
        "be_hw1.npy",
        npy(1, ">f4", "(2, 3, 1)", false, &be32),
    );
    seeds.put("npy", "v2.npy", npy(2, "<f4", "(3, 2)", false, &le32));
    seeds.put(
        "npy",
        "int.npy",
        npy(1, "<i4", "(1, 2)", false, &[1, 0, 0, 0, 2, 0, 0, 0]),
    );
    let le16: Vec<u8> = small
        .iter()
        .flat_map(|v| half::f16::from_f32(*v).to_le_bytes())
        .collect();
    let f_px = npy(1, "<f8", "()", false, &1234f64.to_le_bytes());
    seeds.put(
        "npz",
        "savez_f2.npz",
        npz(&[("arr_0", npy(1, "<f2", "(2, 3)", false, &le16))], false),
    );
    seeds.put(
        "npz",
        "depth_pro.npz",
        npz(
            &[
                ("focallength_px", f_px),
                ("depth", npy(1, "<f4", "(2, 3)", false, &le32)),
            ],
            true,
        ),
    );

    let rgb: Vec<u8> = (0..4 * 4 * 3).map(|i| (i * 37 % 256) as u8).collect();
    let rgba16: Vec<u8> = (0..2 * 2 * 4 * 2).map(|i| (i * 53 % 256) as u8).collect();
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 80).encode(
        &rgb,
        4,
        4,
        image::ExtendedColorType::Rgb8,
    )?;
    seeds.put(
        "colour_image",
        "rgb8.png",
        png(&rgb, 4, 4, image::ExtendedColorType::Rgb8)?,
    );
    seeds.put(
        "colour_image",
        "rgba16.png",
        png(&rgba16, 2, 2, image::ExtendedColorType::Rgba16)?,
    );
    seeds.put("colour_image", "grey8.png", png8.clone());
    seeds.put("colour_image", "rgb.jpg", jpeg.clone());
    // A phone photo's orientation tag (applied) and 35 mm equivalent focal length, read from
    // a JPEG's APP1 and a PNG's eXIf chunk: EXIF is a TIFF structure of its own, in either
    // byte order.
    seeds.put(
        "colour_image",
        "exif-rotate90.jpg",
        tagged(&rgb, 4, 4, exif_orientation(6, Some(26), false), true)?,
    );
    seeds.put(
        "colour_image",
        "exif-mirror.png",
        tagged(&rgb, 4, 4, exif_orientation(2, Some(28), true), false)?,
    );
    // Renderers' linear float frames: flat R, G, B beside a depth Z; Blender's multilayer
    // names in half floats; a colour PFM.
    let hdr = [0.25f32, 3.5, 0.0, 1.0, 64.0, 0.5];
    let halves = || FlatSamples::F16(hdr.iter().map(|&v| half::f16::from_f32(v)).collect());
    let f32s = || FlatSamples::F32(hdr.to_vec());
    let rgbz = vec![("R", f32s()), ("G", f32s()), ("B", f32s()), ("Z", z())];
    let blender = vec![
        ("ViewLayer.Combined.R", halves()),
        ("ViewLayer.Combined.G", halves()),
        ("ViewLayer.Combined.B", halves()),
        ("ViewLayer.Combined.A", halves()),
        ("ViewLayer.Depth.Z", z()),
        ("ViewLayer.Mist.Z", halves()),
    ];
    seeds.put(
        "colour_image",
        "rgbz.exr",
        exr(rgbz, Compression::ZIP16, false)?,
    );
    let blender = exr(blender, Compression::ZIP16, false)?;
    seeds.put("colour_image", "blender.exr", blender.clone());
    seeds.put("exr", "blender.exr", blender);
    seeds.put("colour_image", "rgb.pfm", pfm("PF", 3, 2, &hdr, true, "\n"));
    // Photos with ICC profiles (tests/data/colour/): a gamma curve decoded by itself, a
    // table curve, a profile that is none, a grey profile on RGB pixels; and colour
    // spaces stated by chunks (gAMA, cHRM, cICP, the HDR one refused); a WebP and a TIFF
    // with both, a 16-bit and a float TIFF.
    for name in [
        "gamma22-ramp.png",
        "p3-flat.png",
        "garbage-icc.png",
        "grey-icc.png",
        "gama-linear-ramp.png",
        "chrm-p3-flat.png",
        "cicp-linear-ramp.png",
        "cicp-pq-flat.png",
        "gamma22-ramp.webp",
        "gamma22-ramp.tif",
        "ramp16.tif",
        "ramp-float.tif",
    ] {
        let png = std::fs::read(root.join("tests/data/colour").join(name))?;
        seeds.put("colour_image", &format!("icc-{name}"), png);
    }
    // And a JPEG's APP2 profile, stored as it is (a PNG's is compressed, which mutations
    // mostly break).
    let ramp = std::fs::read(root.join("tests/data/colour/gamma22-ramp.png"))?;
    let mut decoder = image::codecs::png::PngDecoder::new(std::io::Cursor::new(&ramp))?;
    let icc = image::ImageDecoder::icc_profile(&mut decoder)?.expect("the ramp's profile");
    let mut icc_jpeg = Vec::new();
    let mut encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut icc_jpeg, 90);
    image::ImageEncoder::set_icc_profile(&mut encoder, icc)?;
    image::ImageEncoder::write_image(encoder, &rgb, 4, 4, image::ExtendedColorType::Rgb8)?;
    seeds.put("colour_image", "icc-gamma22.jpg", icc_jpeg);
    // exif_out: an output's size (two little-endian u16, the second x16), then the EXIF
    // blocks ExifTool wrote (tests/data/exif/): little-endian with a thumbnail IFD,
    // big-endian.
    for (name, file) in [("le-thumb", "rot6.jpg"), ("be", "big-endian.png")] {
        let bytes = std::fs::read(root.join("tests/data/exif").join(file))?;
        let mut decoder = image::ImageReader::new(std::io::Cursor::new(&bytes))
            .with_guessed_format()?
            .into_decoder()?;
        let block = image::ImageDecoder::exif_metadata(&mut decoder)?.expect("the fixture's");
        let mut seed = vec![16, 0, 2, 0];
        seed.extend_from_slice(&block);
        seeds.put("exif_out", &format!("{name}.bin"), seed);
    }

    // gdepth: the small JPEGs of tests/data/gdepth/ (ext8.jpg in extended XMP, dd8.jpg
    // Dynamic Depth, conf8.jpg with a confidence map).
    for name in ["inv8.jpg", "lin16.jpg", "ext8.jpg", "dd8.jpg", "conf8.jpg"] {
        let jpeg = std::fs::read(root.join("tests/data/gdepth").join(name))?;
        seeds.put("gdepth", name, jpeg);
    }
    // And an iPhone's portrait, whose depth is an image its MPF index lists (after a
    // matte), and a depth image in metres.
    for name in ["portrait.jpg", "depth-abs.jpg"] {
        let jpeg = std::fs::read(root.join("tests/data/apple").join(name))?;
        seeds.put("gdepth", &format!("apple-{name}"), jpeg);
    }

    // load_range: extension index (0 png, 1 pfm, 2 exr, 3 tif, 4 tiff, 5 npy, 6 jpg, 7 npz)
    // with bit 3 set when a calib.txt follows, two option bytes, then the calib's length
    // and text if any, then the file.
    let load = |head: u8, a: u8, b: u8, calib: Option<&str>, file: &[u8]| {
        let mut v = vec![head, a, b];
        if let Some(text) = calib {
            v.extend_from_slice(&(text.len() as u16).to_le_bytes());
            v.extend_from_slice(text.as_bytes());
        }
        v.extend_from_slice(file);
        v
    };
    let disp = pfm("Pf", 12, 9, &floats, true, "\n");
    seeds.put(
        "load_range",
        "m2014.bin",
        load(1 | 8, 0, 0, Some(&calib), &disp),
    );
    seeds.put(
        "load_range",
        "m2014_forced.bin",
        load(1 | 8, 1, 0, Some(&calib), &disp),
    );
    seeds.put(
        "load_range",
        "pfm_disp.bin",
        load(1, 3 << 3 | 0xC0, 1, None, &disp),
    );
    seeds.put("load_range", "png8.bin", load(0, 0, 0, None, &png8));
    seeds.put("load_range", "png16_kitti.bin", load(0, 3, 0, None, &png16));
    seeds.put(
        "load_range",
        "exr.bin",
        load(
            2,
            0x40,
            0,
            None,
            &exr(vec![("Z", z())], Compression::ZIP1, false)?,
        ),
    );
    seeds.put(
        "load_range",
        "npy.bin",
        load(5, 2 << 3, 0, None, &npy(1, "<f4", "(2, 3)", false, &le32)),
    );
    seeds.put("load_range", "jpg.bin", load(6, 0, 0, None, &jpeg));
    let mm: Vec<u8> = [0u16, 1000, 2560, 7]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let uint16 = npz(&[("depth", npy(1, "<u2", "(2, 2)", false, &mm))], true);
    seeds.put("load_range", "npz_kitti.bin", load(7, 3, 0, None, &uint16));

    // Cityscapes camera files: the dataset's own (every key), the keys brume reads alone,
    // the limits of each accepted range, and numbers in exponent form.
    let camera = |b: &str, fx: &str, fy: &str, u0: &str, v0: &str| {
        format!(
            "{{\"extrinsic\": {{\"baseline\": {b}}}, \
             \"intrinsic\": {{\"fx\": {fx}, \"fy\": {fy}, \"u0\": {u0}, \"v0\": {v0}}}}}\n"
        )
        .into_bytes()
    };
    seeds.put("camera", "aachen_camera.json", CITYSCAPES_CAMERA.into());
    seeds.put(
        "camera",
        "minimal.json",
        camera("0.5", "20", "25.0", "3.5", "1.25"),
    );
    seeds.put(
        "camera",
        "limits_low.json",
        camera("0.001", "1", "1", "-16384", "-16384"),
    );
    seeds.put(
        "camera",
        "limits_high.json",
        camera("1000", "1e6", "1E+6", "32768", "32768.0"),
    );
    seeds.put(
        "camera",
        "exponents.json",
        camera(
            "2.09313e-1",
            "2.26252E3",
            "22.653e2",
            "1096.98",
            "5.13137e+2",
        ),
    );

    // CSV manifests of `brume batch`: Cityscapes' triplets, every column with empty
    // cells, comments, blank lines and CRLF; a spreadsheet's byte-order mark and capitals.
    let manifests: [(&str, &str); 4] = [
        (
            "cityscapes.csv",
            "image,depth,camera\n\
             leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit.png,\
             disparity/train/aachen/aachen_000000_000019_disparity.png,\
             camera/train/aachen/aachen_000000_000019_camera.json\n\
             leftImg8bit/val/bonn/b_leftImg8bit.png,disparity/val/bonn/b_disparity.png,\
             camera/val/bonn/b_camera.json\n",
        ),
        (
            "all_columns.csv",
            "# frames to fog\r\nimage, depth, camera, calib, sky_mask\r\n\r\n\
             a/im0.png, a/disp0.pfm, , a/calib.txt, masks/a.png\r\n\
             # skipped\r\n/abs/b.jpg,/abs/b.exr,,,\r\n",
        ),
        (
            "bom_capitals.csv",
            "\u{feff}Depth,IMAGE,Sky_Mask\nd/1.png,i/1.png,m/1_gtFine_labelIds.png\n",
        ),
        (
            "middlebury.csv",
            "image,depth,calib\nAloe/im0.png,Aloe/disp0.pfm,Aloe/calib.txt\n\
             Bike/im0.png,Bike/disp0.pfm,Bike/calib.txt\n",
        ),
    ];
    for (name, text) in manifests {
        seeds.put("manifest", name, text.into());
    }

    // Sky masks: the first byte picks the format (0 binary, 1 Cityscapes labelIds,
    // 2 trainIds), the rest is the PNG.
    let mask = |format: u8, png: &[u8]| [&[format][..], png].concat();
    let binary: Vec<u8> = (0..12).map(|i| if i < 5 { 255 } else { 0 }).collect();
    let label_ids: Vec<u8> = [23, 23, 23, 7, 11, 21, 26, 24, 0, 1, 23, 7].into();
    let train_ids: Vec<u8> = [10, 10, 10, 0, 2, 8, 13, 11, 255, 255, 10, 0].into();
    let labels16: Vec<u16> = label_ids.iter().map(|&v| u16::from(v)).collect();
    let grey = image::ExtendedColorType::L8;
    seeds.put(
        "sky_mask",
        "binary.bin",
        mask(0, &png(&binary, 4, 3, grey)?),
    );
    seeds.put(
        "sky_mask",
        "labelids.bin",
        mask(1, &png(&label_ids, 4, 3, grey)?),
    );
    seeds.put(
        "sky_mask",
        "trainids.bin",
        mask(2, &png(&train_ids, 4, 3, grey)?),
    );
    seeds.put(
        "sky_mask",
        "labelids16.bin",
        mask(
            1,
            &png(&be16(&labels16), 4, 3, image::ExtendedColorType::L16)?,
        ),
    );
    seeds.put("sky_mask", "grey_alpha.bin", mask(0, &png_la));
    // Cityscapes' colours (sky is 70, 130, 180), as a binary mask would be given by mistake.
    let colours = [70, 130, 180, 128, 64, 128, 0, 0, 0, 70, 130, 180];
    seeds.put(
        "sky_mask",
        "colour.bin",
        mask(0, &png(&colours, 2, 2, image::ExtendedColorType::Rgb8)?),
    );
    let palette = [[0, 0, 0], [70, 130, 180], [128, 64, 128]];
    seeds.put(
        "sky_mask",
        "palette.bin",
        mask(0, &palette_png(4, 2, &palette, &[1, 1, 1, 2, 0, 2, 1, 0])),
    );

    // Transmittance maps: 8-bit grey as Foggy Cityscapes publishes them, 16-bit grey, an
    // RGB map whose channels agree, and a palette of colours (refused after decoding).
    let tau: Vec<u8> = crop.iter().map(|&d| 255 - d).collect();
    seeds.put("transmittance_map", "grey8.png", png(&tau, 12, 9, grey)?);
    let tau16: Vec<u16> = tau.iter().map(|&t| u16::from(t) * 257).collect();
    seeds.put(
        "transmittance_map",
        "grey16.png",
        png(&be16(&tau16), 12, 9, image::ExtendedColorType::L16)?,
    );
    let tau_rgb: Vec<u8> = tau[..12].iter().flat_map(|&t| [t, t, t]).collect();
    seeds.put(
        "transmittance_map",
        "rgb.png",
        png(&tau_rgb, 4, 3, image::ExtendedColorType::Rgb8)?,
    );
    seeds.put(
        "transmittance_map",
        "palette.png",
        palette_png(4, 2, &palette, &[1, 1, 1, 2, 0, 2, 1, 0]),
    );

    // CSV tables: byte 0 picks the density table (even) or the spectral sensitivity (odd).
    let tables = [
        (
            "density.csv",
            0,
            "# fog bank\nheight_m,extinction_per_m\n0,0.02\n50,0.01\n200,0\n",
        ),
        (
            "density_bom.csv",
            2,
            "\u{feff}height_m , extinction_per_m\r\n-10,0.5 # below sea level\r\n1e3,1e-4\r\n",
        ),
        (
            "sensitivity.csv",
            1,
            "lambda_nm,r,g,b\n380,0,0,0.01\n450,0.02,0.1,0.9\n550,0.1,0.95,0.1\n\
             600,0.8,0.3,0\n700,0.4,0,0\n780,0,0,0\n",
        ),
        (
            "sensitivity_bare.csv",
            3,
            "# no header\n400,0.1,0.2,0.9\n500,0.2,0.9,0.3\n600,0.9,0.2,-0.01\n",
        ),
    ];
    for (name, which, text) in tables {
        seeds.put("tables", name, [&[which][..], text.as_bytes()].concat());
    }

    // RFC 3339 times, as `--time` takes them.
    for (name, time) in [
        ("offset.txt", "2003-10-17T12:30:30-07:00"),
        ("utc.txt", "2024-06-21T10:00:00Z"),
        ("fraction_space.txt", "1999-12-31 23:59:59.125+05:45"),
        ("leap_day.txt", "2000-02-29t00:00:00z"),
    ] {
        seeds.put("sun_time", name, time.into());
    }
    seeds.finish()
}

/// A Cityscapes camera file as the dataset ships it (`aachen_000000_000019_camera.json`).
const CITYSCAPES_CAMERA: &str = r#"{
    "extrinsic": {
        "baseline": 0.209313,
        "pitch": 0.038,
        "roll": 0.0,
        "x": 1.7,
        "y": 0.1,
        "yaw": -0.0195,
        "z": 1.18
    },
    "intrinsic": {
        "fx": 2262.52,
        "fy": 2265.3017905988554,
        "u0": 1096.98,
        "v0": 513.137
    }
}
"#;

/// Writes seeds, one folder per fuzz target, and counts them.
struct Seeds {
    out: PathBuf,
    written: Vec<(String, usize)>,
    error: Option<std::io::Error>,
}

impl Seeds {
    fn new(out: &Path) -> Self {
        Seeds {
            out: out.to_path_buf(),
            written: Vec::new(),
            error: None,
        }
    }

    fn put(&mut self, target: &str, name: &str, bytes: Vec<u8>) {
        let dir = self.out.join(target);
        let result =
            std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(dir.join(name), &bytes));
        match result {
            Ok(()) => self.written.push((format!("{target}/{name}"), bytes.len())),
            Err(e) => self.error = self.error.take().or(Some(e)),
        }
    }

    fn finish(self) -> Res<()> {
        if let Some(e) = self.error {
            return Err(e.into());
        }
        let total: usize = self.written.iter().map(|w| w.1).sum();
        for (name, len) in &self.written {
            println!("{len:6} {name}");
        }
        println!(
            "{} seeds, {total} bytes, in {}",
            self.written.len(),
            self.out.display()
        );
        Ok(())
    }
}

fn pfm(magic: &str, w: usize, h: usize, values: &[f32], little: bool, eol: &str) -> Vec<u8> {
    let scale = if little { "-1.0" } else { "1.0" };
    let mut b = format!("{magic}{eol}{w} {h}{eol}{scale}{eol}").into_bytes();
    let channels = if magic == "PF" { 3 } else { 1 };
    // Rows bottom to top; values repeat when a colour file needs more than given.
    for i in 0..w * h * channels {
        let v = values[i % values.len()];
        b.extend_from_slice(&if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        });
    }
    b
}

fn calib_txt(w: usize, h: usize) -> String {
    format!(
        "cam0=[1000 0 5.5; 0 1000 4; 0 0 1]\ncam1=[1000 0 15.5; 0 1000 4; 0 0 1]\n\
         doffs=10\nbaseline=200\nwidth={w}\nheight={h}\nndisp=100\nisint=0\nvmin=1\nvmax=90\n"
    )
}

/// 16-bit samples in the byte order `image::save_buffer` and the PNG encoder take.
fn be16(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_ne_bytes()).collect()
}

fn png(bytes: &[u8], w: u32, h: u32, colour: image::ExtendedColorType) -> Res<Vec<u8>> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out).write_image(bytes, w, h, colour)?;
    Ok(out)
}

/// An RGB image as JPEG or PNG carrying the EXIF block `exif`.
fn tagged(rgb: &[u8], w: u32, h: u32, exif: Vec<u8>, jpeg: bool) -> Res<Vec<u8>> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    let colour = image::ExtendedColorType::Rgb8;
    if jpeg {
        let mut e = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 80);
        e.set_exif_metadata(exif)?;
        e.write_image(rgb, w, h, colour)?;
    } else {
        let mut e = image::codecs::png::PngEncoder::new(&mut out);
        e.set_exif_metadata(exif)?;
        e.write_image(rgb, w, h, colour)?;
    }
    Ok(out)
}

/// An EXIF block (TIFF) holding orientation `value` in IFD0 and, if given, a pointer to an
/// Exif IFD holding `FocalLengthIn35mmFilm` `focal_35mm`, in either byte order.
fn exif_orientation(value: u16, focal_35mm: Option<u16>, big_endian: bool) -> Vec<u8> {
    let u16b = |v: u16| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let u32b = |v: u32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let mut b = if big_endian {
        b"MM".to_vec()
    } else {
        b"II".to_vec()
    };
    // An entry whose one SHORT or LONG value is held in it.
    let entry = |b: &mut Vec<u8>, tag: u16, long: Option<u32>, short: u16| {
        b.extend(u16b(tag));
        b.extend(u16b(if long.is_some() { 4 } else { 3 }));
        b.extend(u32b(1));
        match long {
            Some(v) => b.extend(u32b(v)),
            None => {
                b.extend(u16b(short));
                b.extend([0, 0]);
            }
        }
    };
    b.extend(u16b(42));
    b.extend(u32b(8)); // the first IFD
    let entries = 1 + u16::from(focal_35mm.is_some());
    b.extend(u16b(entries));
    entry(&mut b, 0x0112, None, value); // Orientation

    // IFD0 ends at 8 + 2 + 12 entries + 4: the Exif IFD follows.
    let exif_ifd = 8 + 2 + 12 * u32::from(entries) + 4;
    if focal_35mm.is_some() {
        entry(&mut b, 0x8769, Some(exif_ifd), 0); // ExifIFDPointer
    }
    b.extend(u32b(0)); // no next IFD
    if let Some(mm) = focal_35mm {
        b.extend(u16b(1));
        entry(&mut b, 0xA405, None, mm); // FocalLengthIn35mmFilm
        b.extend(u32b(0));
    }
    b
}

/// An 8-bit palette PNG (colour type 3), which the image crate's encoder does not write:
/// chunks by hand, the pixels in one stored (uncompressed) deflate block.
fn palette_png(w: u32, h: u32, palette: &[[u8; 3]], indices: &[u8]) -> Vec<u8> {
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let start = out.len();
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        let crc = crc32fast::hash(&out[start..]);
        out.extend_from_slice(&crc.to_be_bytes());
    }
    let mut raw = Vec::new();
    for row in indices.chunks(w as usize) {
        raw.push(0); // filter: none
        raw.extend_from_slice(row);
    }
    let mut zlib = vec![0x78, 0x01, 1];
    zlib.extend_from_slice(&(raw.len() as u16).to_le_bytes());
    zlib.extend_from_slice(&(!(raw.len() as u16)).to_le_bytes());
    zlib.extend_from_slice(&raw);
    let (mut a, mut b) = (1u32, 0u32);
    for &x in &raw {
        a = (a + u32::from(x)) % 65521;
        b = (b + a) % 65521;
    }
    zlib.extend_from_slice(&(b << 16 | a).to_be_bytes());
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 3, 0, 0, 0]);
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(&mut out, b"PLTE", palette.as_flattened());
    chunk(&mut out, b"IDAT", &zlib);
    chunk(&mut out, b"IEND", &[]);
    out
}

/// `side`² values rising smoothly from 0.5 to about 2.5 (row by row), which compress.
fn ramp(side: usize) -> impl Iterator<Item = f32> {
    (0..side * side).map(move |i| 0.5 + (i / side + i % side) as f32 / side as f32)
}

/// A `side` x `side` scan-line EXR of `channels`.
fn exr_sized(
    channels: Vec<(&str, exr::prelude::FlatSamples)>,
    compression: exr::prelude::Compression,
    side: usize,
) -> Res<Vec<u8>> {
    exr_of((side, side), channels, compression, false)
}

fn exr(
    channels: Vec<(&str, exr::prelude::FlatSamples)>,
    compression: exr::prelude::Compression,
    tiled: bool,
) -> Res<Vec<u8>> {
    exr_of((3, 2), channels, compression, tiled)
}

fn exr_of(
    size: (usize, usize),
    channels: Vec<(&str, exr::prelude::FlatSamples)>,
    compression: exr::prelude::Compression,
    tiled: bool,
) -> Res<Vec<u8>> {
    use exr::prelude::*;
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .into_iter()
        .map(|(name, data)| AnyChannel::new(name, data))
        .collect();
    let blocks = if tiled {
        Blocks::Tiles(Vec2(2, 2))
    } else {
        Blocks::ScanLines
    };
    let encoding = Encoding {
        compression,
        blocks,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        encoding,
        AnyChannels::sort(list),
    );
    let mut out = Vec::new();
    Image::from_layer(layer)
        .write()
        .to_buffered(Cursor::new(&mut out))?;
    Ok(out)
}

type TiffEncoder<'a> = tiff::encoder::TiffEncoder<&'a mut Cursor<Vec<u8>>>;

/// The bytes of an uncompressed TIFF that `write` encodes.
fn tiff(write: impl FnOnce(&mut TiffEncoder) -> tiff::TiffResult<()>) -> Res<Vec<u8>> {
    tiff_with(tiff::encoder::Compression::Uncompressed, write)
}

/// The bytes of a TIFF that `write` encodes with `compression`.
fn tiff_with(
    compression: tiff::encoder::Compression,
    write: impl FnOnce(&mut TiffEncoder) -> tiff::TiffResult<()>,
) -> Res<Vec<u8>> {
    let mut buf = Cursor::new(Vec::new());
    write(&mut tiff::encoder::TiffEncoder::new(&mut buf)?.with_compression(compression))?;
    Ok(buf.into_inner())
}

/// A .npz archive as `np.savez` (stored) or `np.savez_compressed` (deflated) writes it.
fn npz(arrays: &[(&str, Vec<u8>)], deflated: bool) -> Vec<u8> {
    use std::io::Write;
    let method = if deflated {
        zip::CompressionMethod::Deflated
    } else {
        zip::CompressionMethod::Stored
    };
    let options = zip::write::SimpleFileOptions::default().compression_method(method);
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    for (name, array) in arrays {
        zip.start_file(format!("{name}.npy"), options).unwrap();
        zip.write_all(array).unwrap();
    }
    zip.finish().unwrap().into_inner()
}

/// A .npy file as numpy writes it: header padded to a multiple of 64 bytes.
fn npy(version: u8, descr: &str, shape: &str, fortran: bool, data: &[u8]) -> Vec<u8> {
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    let preamble = if version == 1 { 10 } else { 12 };
    while (preamble + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut b = b"\x93NUMPY".to_vec();
    b.extend_from_slice(&[version, 0]);
    if version == 1 {
        b.extend_from_slice(&(header.len() as u16).to_le_bytes());
    } else {
        b.extend_from_slice(&(header.len() as u32).to_le_bytes());
    }
    b.extend_from_slice(header.as_bytes());
    b.extend_from_slice(data);
    b
}
