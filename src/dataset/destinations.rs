//! What a batch proves about a dataset before it makes anything: every frame's outputs lie
//! under the output folder (after `..` and links) and are that frame's alone, and a shared
//! sky mask has every frame's size.

use super::Item;
use crate::error::{Error, Result};
use crate::io::output::{file_id, FileId};
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

/// A sky mask shared by the frames without their own has each such frame's size: refused
/// up front, from the files' headers, rather than frame by frame.
pub(super) fn check_sky_mask_size(mask: &Path, items: &[Item]) -> Result<()> {
    let size = crate::io::image::read_image_dimensions;
    let (mw, mh) = size(mask).map_err(|e| match e {
        Error::Io { .. } | Error::Format { .. } => Error::invalid(
            "sky_mask",
            mask.display(),
            format!("a readable PNG sky mask ({e})"),
        ),
        e => e,
    })?;
    for item in items.iter().filter(|i| i.sky_mask.is_none()) {
        let (w, h) = size(&item.image)?;
        if (w, h) != (mw, mh) {
            return Err(Error::invalid(
                "sky_mask",
                format!("{} ({mw}x{mh})", mask.display()),
                format!(
                    "a mask of each frame's size: {} is {w}x{h}",
                    item.image.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Proves that every output of every frame (its fogged image at each of `betas`, and its
/// transmittance map with `transmittance`) lies under `out` (after `..` and links are
/// resolved), that no two frames write one file (`X.png` and `X.jpg` in one folder, a
/// row given twice, a folder given twice) and that none is a file a frame reads (a
/// manifest that lists an earlier run's outputs beside their frames, into the same
/// folder: `a_foggy_beta_0.01.png` was taken as `a.png`'s output, complete, and written
/// over when its τ map was missing), before any work.
pub(super) fn check_destinations(
    out: &Path,
    transmittance: bool,
    items: &[Item],
    betas: &[f64],
) -> Result<()> {
    let mut owners: HashMap<PathBuf, &Path> = HashMap::new();
    for item in items {
        let out_dir = contained_dir(&item.out_dir).ok_or_else(|| {
            Error::invalid(
                "inputs",
                item.image.display(),
                format!(
                    "a frame whose outputs stay under the output folder: its folder `{}` \
                     climbs out",
                    item.out_dir.display()
                ),
            )
        })?;
        check_no_link_out(out, &out_dir, item)?;
        let normalised = Item {
            out_dir,
            ..item.clone()
        };
        let here = Path::new("");
        for &beta in betas {
            let paths = std::iter::once(normalised.foggy_output(here, beta))
                .chain(transmittance.then(|| normalised.transmittance_output(here, beta)));
            for path in paths {
                let Some(other) = owners.insert(path.clone(), &item.image) else {
                    continue;
                };
                let expected = if other == item.image {
                    "each frame once: it is given twice (a repeated manifest row, or one \
                     folder twice)"
                        .to_string()
                } else {
                    format!(
                        "frames with outputs of their own: {} also writes {}",
                        other.display(),
                        out.join(&path).display()
                    )
                };
                return Err(Error::invalid("inputs", item.image.display(), expected));
            }
        }
    }
    refuse_outputs_read(out, &owners, items)
}

/// Refuses an output (`owners`: each one's path under `out`, with the frame that writes
/// it) that is a file some frame reads, through a link or not. Only outputs that exist
/// can be (an input that does not is a frame that fails), so a new folder's run looks up
/// no input.
fn refuse_outputs_read(out: &Path, owners: &HashMap<PathBuf, &Path>, items: &[Item]) -> Result<()> {
    let mut outputs: Vec<(&PathBuf, &&Path)> = owners.iter().collect();
    outputs.sort();
    let mut read = None;
    for (path, writer) in outputs {
        let output = out.join(path);
        let Some(id) = file_id(&output) else {
            continue;
        };
        if let Some(input) = read.get_or_insert_with(|| files_read(items)).get(&id) {
            return Err(Error::invalid(
                "inputs",
                writer.display(),
                format!(
                    "a frame whose outputs are none of the inputs: it writes {}, which is \
                     {}, a file a frame reads",
                    output.display(),
                    input.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Every file the frames read that exists, by its [`FileId`].
fn files_read(items: &[Item]) -> HashMap<FileId, &Path> {
    let mut read = HashMap::new();
    for item in items {
        let files = [Some(&item.image), Some(&item.depth)]
            .into_iter()
            .chain([&item.camera, &item.calib, &item.sky_mask].map(Option::as_ref))
            .flatten();
        for file in files {
            if let Some(id) = file_id(file) {
                read.insert(id, file.as_path());
            }
        }
    }
    read
}

/// `dir` with `.` and `x/..` removed, if it stays inside the folder it is relative to
/// (no `..` above it, no root, no drive).
fn contained_dir(dir: &Path) -> Option<PathBuf> {
    let mut parts: Vec<&std::ffi::OsStr> = Vec::new();
    for c in dir.components() {
        match c {
            Component::Normal(p) => parts.push(p),
            Component::CurDir => {}
            Component::ParentDir => {
                parts.pop()?;
            }
            Component::RootDir | Component::Prefix(_) => return None,
        }
    }
    Some(parts.iter().collect())
}

/// Refuses an output folder that exists under `out` through a symbolic link to a place
/// outside `out`: the outputs would be written there.
fn check_no_link_out(out: &Path, out_dir: &Path, item: &Item) -> Result<()> {
    let Ok(root) = out.canonicalize() else {
        return Ok(()); // the output folder does not exist yet: nor does anything under it
    };
    let mut dir = out.to_path_buf();
    for part in out_dir.components() {
        dir.push(part);
        match dir.canonicalize() {
            Ok(real) if !real.starts_with(&root) => {
                return Err(Error::invalid(
                    "out",
                    out.display(),
                    format!(
                        "a folder whose sub-folders stay inside it: {} (the outputs of {}) \
                         leads to {}",
                        dir.display(),
                        item.image.display(),
                        real.display()
                    ),
                ))
            }
            Ok(_) => {}
            Err(_) => break, // made by the run, inside the output folder
        }
    }
    Ok(())
}
