//! Writing results. Every writer goes through a temporary file in the destination's
//! directory that is renamed over the destination only once complete, so a crash or an
//! error never leaves a partial file and never damages an existing one.
//!
//! A command that writes several files stages them all in an [`Outputs`] set and renames
//! them together once every one is complete: all are written or none is touched. Live
//! temporaries are known to `exit_removing_temporaries` (the `cli` feature), which a
//! program's signal handler calls so that an interrupt leaves no `.brume-*.tmp` behind.
//!
//! An output named by a symbolic link replaces the file the link leads to, and the link is
//! kept (a rename onto the link would replace the link itself and leave its file as it
//! was); one that is a named pipe or a device is written into, not replaced.
//!
//! This module owns the path checks, that atomic write and the choice of format by
//! extension; the bytes of each format come from its codec in `io::codec`, next to the
//! reader of the same format.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use crate::io::codec::{exr, jpeg, pfm, png};
use crate::io::colour_profile::ColourProfile;
use crate::io::metadata::PhotoMetadata;
use crate::io::srgb::linear_rgba_to_srgb8_rgb;
use crate::raster::{RgbaImage, ScalarMap};
use crate::{Error, Result};

/// Extensions [`write_rgba`] accepts.
pub const IMAGE_EXTENSIONS: [&str; 5] = ["png", "jpg", "jpeg", "pfm", "exr"];
/// Extensions [`write_scalar`] accepts.
pub const SCALAR_EXTENSIONS: [&str; 2] = ["pfm", "exr"];
/// Extensions [`write_png_rgb8`] accepts: it writes PNG bytes, so nothing else.
pub const PNG_EXTENSIONS: [&str; 1] = ["png"];

/// Checks, before any work is done, that `path` can take an image output: a known
/// extension and an existing directory. `option` names the flag in the error.
pub fn check_image_output(path: &Path, option: &str) -> Result<()> {
    check_output(path, option, &IMAGE_EXTENSIONS)
}

/// Like [`check_image_output`] for scalar maps (`.pfm`, `.exr`).
pub fn check_scalar_output(path: &Path, option: &str) -> Result<()> {
    check_output(path, option, &SCALAR_EXTENSIONS)
}

/// Like [`check_image_output`] for pictures that are always PNG (visualisations).
pub fn check_png_output(path: &Path, option: &str) -> Result<()> {
    check_output(path, option, &PNG_EXTENSIONS)
}

/// Checks, before any work is done, that `path` ends in one of `extensions` (lower case,
/// without the dot) and can be renamed onto; `option` names the flag in the error.
pub fn check_output(path: &Path, option: &str, extensions: &[&str]) -> Result<()> {
    if !extensions.contains(&extension_of(path).as_str()) {
        return Err(Error::invalid(
            option,
            path.display(),
            format!("a path ending in {}", list_extensions(extensions)),
        ));
    }
    check_destination(path, option)
}

/// Checks that `path` can be renamed onto: its directory exists, it is not itself a
/// directory (a rename onto one fails only after all the work is done), and it is not a
/// read-only file.
pub fn check_destination(path: &Path, option: &str) -> Result<()> {
    let dest = followed_links(path);
    if dest.is_dir() {
        return Err(Error::invalid(
            option,
            path.display(),
            "a file path, not a directory",
        ));
    }
    refuse_read_only(path, option)?;
    match missing_folder(&dest) {
        Some(dir) => Err(Error::invalid(
            option,
            path.display(),
            format!(
                "a path in an existing directory ({} is not one)",
                dir.display()
            ),
        )),
        None => Ok(()),
    }
}

/// The folder of `path`, where it names one that does not exist.
fn missing_folder(path: &Path) -> Option<&Path> {
    path.parent()
        .filter(|dir| !dir.as_os_str().is_empty() && !dir.is_dir())
}

/// Refuses a destination whose folder does not exist, saying so (the temporary file's
/// creation would fail naming itself, a name the caller never gave).
fn refuse_missing_folder(path: &Path) -> Result<()> {
    match missing_folder(path) {
        Some(dir) => Err(Error::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("its folder {} does not exist", dir.display()),
            ),
        )),
        None => Ok(()),
    }
}

/// Refuses a destination that is a read-only file: renaming onto it would replace it
/// whatever its mode, and a file made read-only is one its owner protected.
fn refuse_read_only(path: &Path, option: &str) -> Result<()> {
    if std::fs::metadata(path).is_ok_and(|m| m.permissions().readonly()) {
        return Err(Error::invalid(
            option,
            path.display(),
            "a file brume may replace: this one is read-only, and brume does not replace a \
             file its owner protected; make it writable (chmod u+w) or choose another name",
        ));
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically (temporary file, then rename), with the same
/// permissions as every other output: for text reports, CSV tables and plots.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut outputs = Outputs::new();
    outputs.stage_bytes(path, bytes)?;
    outputs.commit()
}

/// [`write_bytes`] unless a file is already at `path`: `Ok(false)` then, and nothing
/// written. Of two processes writing one path at once, one writes it.
pub fn write_bytes_unless_present(path: &Path, bytes: &[u8]) -> Result<bool> {
    let mut outputs = Outputs::new();
    outputs.stage_bytes(path, bytes)?;
    outputs.rename_all(true)
}

/// `.png, .pfm or .exr`.
fn list_extensions(extensions: &[&str]) -> String {
    let dotted: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
    match dotted.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

/// Writes a linear-light RGBA image, choosing the format by extension:
/// `.png` 8-bit sRGB RGB (alpha dropped, values clamped to `[0, 1]` and rounded),
/// `.jpg`/`.jpeg` the same pixels as a JPEG (quality [`jpeg::QUALITY`], 4:4:4),
/// `.pfm` float RGB `PF` (linear, little-endian, rows bottom to top),
/// `.exr` float RGBA (linear, 32-bit).
pub fn write_rgba(path: &Path, img: &RgbaImage) -> Result<()> {
    write_photo(path, img, &PhotoMetadata::default())
}

/// [`write_rgba`] for an image of a photo with the colour profile and EXIF `metadata`: a
/// PNG or JPEG carries both ([`ColourProfile::icc`], [`PhotoMetadata::exif_for_output`]),
/// so that the image's colours, date and camera are the photo's.
pub fn write_photo(path: &Path, img: &RgbaImage, metadata: &PhotoMetadata) -> Result<()> {
    let mut outputs = Outputs::new();
    outputs.stage_photo(path, img, metadata)?;
    outputs.commit()
}

/// Writes a scalar map (range, depth, transmittance) by extension: `.pfm` (`Pf`,
/// little-endian, rows bottom to top) or `.exr` (one 32-bit channel named `Y`).
pub fn write_scalar(path: &Path, map: &ScalarMap) -> Result<()> {
    let mut outputs = Outputs::new();
    outputs.stage_scalar(path, map)?;
    outputs.commit()
}

/// Writes an 8-bit RGB PNG from pixels already encoded (a visualisation), row 0 at the
/// top. `rgb` must hold `width * height` pixels.
pub fn write_png_rgb8(path: &Path, width: usize, height: usize, rgb: &[[u8; 3]]) -> Result<()> {
    let mut outputs = Outputs::new();
    outputs.stage_png_rgb8(path, width, height, rgb)?;
    outputs.commit()
}

/// True if `a` and `b` name the same existing file (after resolving links and `..`), so
/// that an output never overwrites an input. False if either does not exist.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b || same_inode(&a, &b),
        _ => false,
    }
}

fn same_inode(a: &Path, b: &Path) -> bool {
    matches!((file_id(a), file_id(b)), (Some(a), Some(b)) if a == b)
}

/// What makes two paths one file: the device and inode (a hard link is the file it
/// links).
#[cfg(unix)]
pub type FileId = (u64, u64);
/// What makes two paths one file: the canonical path.
#[cfg(not(unix))]
pub type FileId = PathBuf;

/// `path`'s [`FileId`], following symbolic links; `None` where it does not exist.
pub fn file_id(path: &Path) -> Option<FileId> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        path.canonicalize().ok()
    }
}

/// The size of 8-bit pixels `rgb` for `path`, checked: `width * height` of them, each
/// side within an image file's 32 bits.
fn rgb8_size(path: &Path, width: usize, height: usize, rgb: &[[u8; 3]]) -> Result<(u32, u32)> {
    if rgb.len() != width * height {
        return Err(Error::invalid(
            "pixel count",
            rgb.len(),
            format!("{width}*{height} pixels for {}", path.display()),
        ));
    }
    match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => Ok((w, h)),
        _ => Err(Error::invalid(
            "image size",
            format!("{width}x{height}"),
            "at most 2^32-1 per side",
        )),
    }
}

fn extension_of(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// The output files of one command, written all or nothing: each `stage_*` call writes a
/// complete temporary file in its destination's directory; [`Outputs::commit`] renames
/// them all onto their destinations. Dropping the set without committing (an error on
/// the way, a panic) removes the temporaries and leaves every destination as it was.
///
/// ```no_run
/// # fn main() -> brume::Result<()> {
/// # let (range, picture) = (brume::raster::Grid::filled(2, 2, 1.0f32), vec![[0u8; 3]; 4]);
/// use brume::io::output::Outputs;
/// let mut outputs = Outputs::new();
/// outputs.stage_scalar("range.pfm".as_ref(), &range)?;
/// outputs.stage_png_rgb8("range.png".as_ref(), 2, 2, &picture)?;
/// outputs.commit()?; // both files, or (on any error above) neither
/// # Ok(())
/// # }
/// ```
#[derive(Default)]
pub struct Outputs {
    staged: Vec<Staged>,
}

/// A complete temporary file (`None` once renamed) and where it goes: the file a link
/// named leads to, renamed onto, or a named pipe or a device, written into
/// (`streamed`).
struct Staged {
    tmp: Option<tempfile::NamedTempFile>,
    dest: PathBuf,
    streamed: bool,
}

impl Outputs {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// The destinations staged so far, in order.
    pub fn destinations(&self) -> impl Iterator<Item = &Path> {
        self.staged.iter().map(|s| s.dest.as_path())
    }

    /// Stages `bytes` for `path` (reports, CSV tables, plots).
    pub fn stage_bytes(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        self.stage_with(path, |w| w.write_all(bytes))
    }

    /// Stages a linear-light RGBA image for `path`, in the format [`write_rgba`] picks.
    pub fn stage_rgba(&mut self, path: &Path, img: &RgbaImage) -> Result<()> {
        self.stage_photo(path, img, &PhotoMetadata::default())
    }

    /// Stages an image of a photo with the colour profile and EXIF `metadata`, as
    /// [`write_photo`] writes it: a PNG or JPEG carries the profile and the EXIF, an EXR
    /// the profile's primaries and white (its `chromaticities`); a PFM, which holds
    /// neither, is written with a warning where the photo's primaries are not sRGB's.
    pub fn stage_photo(
        &mut self,
        path: &Path,
        img: &RgbaImage,
        metadata: &PhotoMetadata,
    ) -> Result<()> {
        let profile = metadata.profile();
        let icc = profile.map(ColourProfile::icc);
        let extension = extension_of(path);
        if let ("pfm", Some(p)) = (extension.as_str(), profile) {
            if !p.primaries_are_srgb() {
                log::warn!(
                    "{}: its linear values are in the photo's primaries ({}), which a PFM \
                     file cannot say; read it as such, or write .exr, .png or .jpg, which \
                     carry them",
                    path.display(),
                    p.description()
                );
            }
        }
        match extension.as_str() {
            "png" | "jpg" | "jpeg" => {
                let rgb = linear_rgba_to_srgb8_rgb(img.as_slice());
                let (w, h) = rgb8_size(path, img.width(), img.height(), &rgb)?;
                let bytes: Vec<u8> = rgb.iter().flatten().copied().collect();
                let exif = metadata.exif_for_output(w, h, &path.display().to_string());
                match extension.as_str() {
                    "png" => {
                        self.stage_with(path, |out| png::write_rgb8(out, &bytes, w, h, icc, exif))
                    }
                    _ => {
                        self.stage_with(path, |out| jpeg::write_rgb8(out, &bytes, w, h, icc, exif))
                    }
                }
            }
            "pfm" => self.stage_with(path, |w| pfm::write_rgba(w, img)),
            "exr" => {
                let chromaticities = profile.map(ColourProfile::chromaticities);
                self.stage_with(path, |w| exr::write_rgba(w, img, chromaticities))
            }
            _ => check_image_output(path, "out"),
        }
    }

    /// Stages a scalar map for `path`, in the format [`write_scalar`] picks.
    pub fn stage_scalar(&mut self, path: &Path, map: &ScalarMap) -> Result<()> {
        match extension_of(path).as_str() {
            "pfm" => self.stage_with(path, |w| pfm::write_scalar(w, map)),
            "exr" => self.stage_with(path, |w| exr::write_scalar(w, map)),
            _ => check_scalar_output(path, "scalar output"),
        }
    }

    /// Stages an 8-bit RGB PNG of already encoded pixels, as [`write_png_rgb8`] writes it.
    pub fn stage_png_rgb8(
        &mut self,
        path: &Path,
        width: usize,
        height: usize,
        rgb: &[[u8; 3]],
    ) -> Result<()> {
        let (w, h) = rgb8_size(path, width, height, rgb)?;
        let bytes: Vec<u8> = rgb.iter().flatten().copied().collect();
        self.stage_with(path, |out| png::write_rgb8(out, &bytes, w, h, None, None))
    }

    /// Runs `write` on a buffered temporary file next to `path` (next to the file it
    /// leads to, if it is a symbolic link; in the system's temporary folder, if it is a
    /// named pipe or a device) and keeps it for [`Outputs::commit`]. A path already
    /// staged in this set, or one that is a directory, is refused: two outputs of one
    /// command never land on one file.
    pub fn stage_with(
        &mut self,
        path: &Path,
        write: impl FnOnce(&mut BufWriter<&File>) -> std::io::Result<()>,
    ) -> Result<()> {
        if let Some(earlier) = self.destinations().find(|d| same_destination(d, path)) {
            return Err(Error::invalid(
                "output",
                path.display(),
                format!("a file other than the output {}", earlier.display()),
            ));
        }
        let dest = followed_links(path);
        if dest.is_dir() {
            return Err(Error::io(
                path,
                std::io::Error::other("is a directory, not a file to write"),
            ));
        }
        refuse_read_only(path, "output")?;
        refuse_missing_folder(&dest)?;
        let streamed = is_pipe_or_device(&dest);
        let tmp = if streamed {
            create_temporary(&std::env::temp_dir(), path)?
        } else {
            create_temporary(folder_of(&dest), path)?
        };
        // Pushed before writing so that an error below drops (removes) it with the set.
        self.staged.push(Staged {
            tmp: Some(tmp),
            dest,
            streamed,
        });
        let staged = self.staged.last().expect("just pushed");
        let tmp = staged.tmp.as_ref().expect("not yet renamed");
        {
            let mut out = BufWriter::new(tmp.as_file());
            write(&mut out).map_err(|e| Error::io(path, e))?;
            out.flush().map_err(|e| Error::io(path, e))?;
        }
        tmp.as_file().sync_all().map_err(|e| Error::io(path, e))
    }

    /// Renames every staged file onto its destination (first writes those for a named pipe
    /// or a device into it, which may wait: a pipe, until a reader opens it). The renames
    /// run while the temporary registry is locked, so a signal handler using
    /// `exit_removing_temporaries` sees either all of them done or none. After the
    /// checks of staging, a rename fails only if the directory changed meanwhile; the
    /// files renamed before it then stay, the others are removed.
    pub fn commit(self) -> Result<()> {
        self.rename_all(false).map(|_| ())
    }

    /// [`Outputs::commit`]; with `keep_existing`, a destination already present is kept
    /// and its temporary removed (`Ok(false)`: not every file was renamed).
    fn rename_all(mut self, keep_existing: bool) -> Result<bool> {
        let mut result = Ok(true);
        // Pipes and devices first, outside the registry's lock: opening a pipe waits for
        // its reader, and a signal handler must meanwhile be able to take the lock and
        // exit. Their temporaries stay staged, removed when the set drops.
        for staged in self.staged.iter().filter(|s| s.streamed) {
            let tmp = staged.tmp.as_ref().expect("each file is placed once");
            let placed = match keep_existing {
                true => Err(std::io::ErrorKind::AlreadyExists.into()),
                false => copy_into(tmp, &staged.dest),
            };
            if !settle(placed, &staged.dest, keep_existing, &mut result) {
                return result;
            }
        }
        let mut live = live_temporaries();
        for staged in self.staged.iter_mut().filter(|s| !s.streamed) {
            let tmp = staged.tmp.take().expect("each file is renamed once");
            live.retain(|p| p != tmp.path());
            // Dropping `e.file` of a failed rename removes the temporary.
            let renamed = match keep_existing {
                true => tmp.persist_noclobber(&staged.dest),
                false => tmp.persist(&staged.dest),
            };
            let placed = renamed.map(drop).map_err(|e| e.error);
            if !settle(placed, &staged.dest, keep_existing, &mut result) {
                break;
            }
        }
        // Unlocked before `self` drops the files not renamed: their drop takes the lock.
        drop(live);
        result
    }
}

/// Folds one destination's outcome into `result`: with `keep_existing`, a destination
/// already there is kept (not every file written); any other error is the result. Returns
/// whether to go on with the others.
fn settle(
    placed: std::io::Result<()>,
    dest: &Path,
    keep_existing: bool,
    result: &mut Result<bool>,
) -> bool {
    match placed {
        Ok(()) => true,
        Err(e) if keep_existing && e.kind() == std::io::ErrorKind::AlreadyExists => {
            *result = Ok(false);
            true
        }
        Err(e) => {
            *result = Err(Error::io(dest, e));
            false
        }
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(tmp) = &self.tmp {
            // Removed under the lock: a signal handler either removes it or never sees it.
            let mut live = live_temporaries();
            let _ = std::fs::remove_file(tmp.path());
            live.retain(|p| p != tmp.path());
        }
    }
}

impl std::fmt::Debug for Outputs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.destinations()).finish()
    }
}

/// Paths of the temporary files this process has open, for [`exit_removing_temporaries`].
static LIVE_TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live_temporaries() -> MutexGuard<'static, Vec<PathBuf>> {
    // A writer that panicked left the list itself consistent.
    LIVE_TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner())
}

/// How many symbolic links [`followed_links`] follows, as Linux's `MAXSYMLINKS`.
const MAX_LINKS: usize = 40;

/// Where writing to `path` lands: the end of the chain of symbolic links at `path` (which
/// need not exist: a shell's `>` creates it), else `path` itself. Links of its folders
/// need no following: a rename within a folder goes through them.
fn followed_links(path: &Path) -> PathBuf {
    let mut at = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        let is_link = std::fs::symlink_metadata(&at).is_ok_and(|m| m.file_type().is_symlink());
        match std::fs::read_link(&at) {
            // An absolute target replaces the folder in `join`.
            Ok(target) if is_link => at = folder_of(&at).join(target),
            _ => break,
        }
    }
    at
}

/// A named pipe, a device or a socket: not a file a rename may replace.
fn is_pipe_or_device(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// The folder `path` is in (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Writes the complete temporary `tmp` into the named pipe or device `dest`.
fn copy_into(tmp: &tempfile::NamedTempFile, dest: &Path) -> std::io::Result<()> {
    let mut bytes = tmp.reopen()?;
    let mut out = std::fs::OpenOptions::new().write(true).open(dest)?;
    std::io::copy(&mut bytes, &mut out)?;
    out.flush()
}

/// Creates an empty temporary in `dir` for the output `path` and registers it, under the
/// registry lock so that a signal handler never misses a file that exists.
fn create_temporary(dir: &Path, path: &Path) -> Result<tempfile::NamedTempFile> {
    let prefix = temporary_prefix();
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(TEMPORARY_SUFFIX);
    #[cfg(unix)]
    {
        // NamedTempFile defaults to 0600; an output image should be readable like any
        // other file the user creates (the umask still applies).
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut live = live_temporaries();
    let tmp = builder.tempfile_in(dir).map_err(|e| Error::io(path, e))?;
    live.push(tmp.path().to_path_buf());
    Ok(tmp)
}

/// The start of every temporary output's name.
pub const TEMPORARY_PREFIX: &str = ".brume-";
/// The end of every temporary output's name.
pub const TEMPORARY_SUFFIX: &str = ".tmp";
/// A temporary not modified for this long belongs to no live writer: a writer keeps one
/// for the encoding of one output (seconds), so after an hour it was left by a process
/// that was killed, on this machine or another that shares the folder.
pub const STALE_TEMPORARY_AGE: std::time::Duration = std::time::Duration::from_secs(3600);

/// `.brume-{host}-{pid}-`: who made a temporary, so that a later run can tell one left by
/// a killed process (SIGKILL runs no clean-up) from one a live process is still writing.
fn temporary_prefix() -> String {
    format!("{TEMPORARY_PREFIX}{}-{}-", this_host(), std::process::id())
}

/// This machine's name, as a temporary's name carries it: letters, digits and dots.
fn this_host() -> String {
    let name = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
    let name: String = name
        .trim()
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '.')
        .collect();
    if name.is_empty() {
        "host".into()
    } else {
        name
    }
}

/// Whether the temporary named `name` (a file name of `temporary_prefix`'s form) was
/// left by a process that is gone: one of this machine whose process no longer runs, or
/// any that has not changed for [`STALE_TEMPORARY_AGE`]. `age` is the time since it was
/// last modified.
pub fn is_stale_temporary(name: &str, age: std::time::Duration) -> bool {
    let Some(body) = name
        .strip_prefix(TEMPORARY_PREFIX)
        .and_then(|n| n.strip_suffix(TEMPORARY_SUFFIX))
    else {
        return false;
    };
    if age >= STALE_TEMPORARY_AGE {
        return true;
    }
    // `{host}-{pid}-{random}`; an older brume's `{random}` alone is left to the age rule.
    let mut parts = body.rsplitn(3, '-');
    let (_random, pid, host) = (parts.next(), parts.next(), parts.next());
    match (host, pid.and_then(|p| p.parse::<u32>().ok())) {
        (Some(host), Some(pid)) if host == this_host() => !process_runs(pid),
        _ => false,
    }
}

fn process_runs(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true // unknown: leave it to the age rule
    }
}

/// Whether `e` is a write refused because the device or the user's disk quota is full
/// (`ENOSPC`, `EDQUOT`), also when an encoder wrapped the OS error in its own: every later
/// write to that device fails too, so a long run should stop rather than go on.
pub fn is_out_of_space(e: &Error) -> bool {
    use std::io::ErrorKind::{QuotaExceeded, StorageFull};
    let Error::Io { source, .. } = e else {
        return false;
    };
    let mut io: &std::io::Error = source;
    loop {
        if matches!(io.kind(), StorageFull | QuotaExceeded) {
            return true;
        }
        match io.get_ref().and_then(|inner| inner.downcast_ref()) {
            Some(inner) => io = inner,
            None => return false,
        }
    }
}

/// Removes, under `dir` and its sub-folders, the temporary outputs that killed brume
/// processes left (see [`is_stale_temporary`]); returns how many. Links are not followed.
pub fn remove_stale_temporaries(dir: &Path) -> Result<usize> {
    let mut removed = 0;
    super::visit_files(dir, &mut |entry, kind| {
        if !kind.is_file() {
            return Ok(());
        }
        let age = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .unwrap_or_default();
        if !is_stale_temporary(&entry.file_name().to_string_lossy(), age) {
            return Ok(());
        }
        let path = entry.path();
        match std::fs::remove_file(&path) {
            Ok(()) => removed += 1,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(Error::io(&path, e)),
        }
        Ok(())
    })?;
    Ok(removed)
}

/// Removes every temporary output file this process has open and exits with `code`,
/// without returning: for a program's SIGINT/SIGTERM handler (the `brume` program
/// installs one). The registry stays locked until the process is gone, so no writer
/// creates or renames a temporary after the clean-up.
#[cfg(feature = "cli")]
pub fn exit_removing_temporaries(code: i32) -> ! {
    let live = live_temporaries();
    for path in live.iter() {
        let _ = std::fs::remove_file(path);
    }
    std::process::exit(code)
}

/// True if writing to `a` and to `b` would land on one file: the same path once links,
/// `.` and `..` are resolved (the file need not exist yet, its directory must), or the
/// same existing file under two names (a hard link).
pub fn same_destination(a: &Path, b: &Path) -> bool {
    match (resolve_destination(a), resolve_destination(b)) {
        (Some(ra), Some(rb)) => ra == rb || same_file(a, b),
        _ => same_file(a, b),
    }
}

/// The absolute, link-free form of `path`, or of its directory joined with its name
/// when the file does not exist yet.
fn resolve_destination(path: &Path) -> Option<PathBuf> {
    if let Ok(p) = path.canonicalize() {
        return Some(p);
    }
    let name = path.file_name()?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    Some(dir.canonicalize().ok()?.join(name))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// While an output waits for a named pipe's reader, the registry of temporaries is not
    /// locked: Ctrl-C's handler takes that lock to remove them and exit, and would wait
    /// for the reader too.
    #[cfg(unix)]
    #[test]
    fn waiting_for_a_pipe_leaves_the_registry_unlocked() {
        use std::io::Read;
        let dir = tempfile::tempdir().unwrap();
        let pipe = dir.path().join("pipe.png");
        let c_path = std::ffi::CString::new(pipe.as_os_str().as_encoded_bytes()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo reads nothing else.
        assert_eq!(unsafe { libc::mkfifo(c_path.as_ptr(), 0o600) }, 0);
        let writer = {
            let pipe = pipe.clone();
            std::thread::spawn(move || write_bytes(&pipe, b"fog"))
        };
        // Time for the writer to reach the pipe's open, where it waits for a reader.
        std::thread::sleep(Duration::from_millis(300));
        // Tried a few times: another test's writer may hold the lock for a moment; the
        // waiting writer would hold it throughout.
        let unlocked = (0..20).any(|_| {
            let free = LIVE_TEMPORARIES.try_lock().is_ok();
            if !free {
                std::thread::sleep(Duration::from_millis(5));
            }
            free
        });
        let mut bytes = Vec::new();
        File::open(&pipe).unwrap().read_to_end(&mut bytes).unwrap();
        writer.join().unwrap().unwrap();
        assert!(
            unlocked,
            "the registry was locked while waiting for the pipe's reader"
        );
        assert_eq!(bytes, b"fog");
    }

    #[test]
    fn stale_temporaries_are_told_from_live_ones() {
        let host = this_host();
        let fresh = Duration::from_secs(1);
        let ours = format!("{}abc123.tmp", temporary_prefix());
        assert!(!is_stale_temporary(&ours, fresh), "this process is alive");
        // No process has pid 2^31 - 2 (Linux's pid_max is at most 2^22).
        let dead = format!(".brume-{host}-2147483646-abc123.tmp");
        assert!(is_stale_temporary(&dead, fresh));
        let elsewhere = ".brume-otherhost.example-2147483646-abc123.tmp";
        assert!(!is_stale_temporary(elsewhere, fresh), "may be live there");
        assert!(is_stale_temporary(elsewhere, STALE_TEMPORARY_AGE));
        assert!(!is_stale_temporary(".brume-Ab3xYz.tmp", fresh));
        assert!(is_stale_temporary(".brume-Ab3xYz.tmp", STALE_TEMPORARY_AGE));
        for other in ["photo.png", ".brume-x.png", "brume-a-1-b.tmp"] {
            assert!(!is_stale_temporary(other, STALE_TEMPORARY_AGE), "{other}");
        }
    }
}
