//! A process forked after brume rendered (a PyTorch `DataLoader`'s workers, Python's
//! `multiprocessing` on Linux) renders too: the child's CPU work gets a thread pool of its
//! own (`brume::parallel`) and its context a display of its own (`brume::egl`). Before,
//! the child's first parallel loop, and then its first draw, waited forever for threads
//! that only the parent had.
//!
//! The fork happens in a process of its own (this test binary run again for this test
//! alone), so that no other test's thread holds a lock when it forks.

use crate::common;
use brume::photo::{self, FogOptions, Photo, PrepareOptions};
use brume::raster::{Grid, RgbaImage};
use brume::Headless;
use std::process::Command;
use std::time::{Duration, Instant};

extern "C" {
    fn fork() -> i32;
    fn waitpid(pid: i32, status: *mut i32, options: i32) -> i32;
    fn kill(pid: i32, signal: i32) -> i32;
    fn _exit(status: i32) -> !;
}

const WNOHANG: i32 = 1;
const SIGKILL: i32 = 9;
/// Set in the process that forks.
const ROLE: &str = "BRUME_FORK_TEST";
const NAME: &str = "fork::a_forked_child_renders_what_its_parent_renders";

/// A photo prepared (sky, holes: brume's parallel CPU loops) and fogged (the GPU).
fn fog_photo(headless: &mut Headless) -> brume::Result<RgbaImage> {
    let (w, h) = (64, 48);
    let image = common::noise_image(w, h, 5);
    let range = Grid::from_fn(w, h, |x, y| {
        if y < 10 || (x + y) % 13 == 0 {
            f32::NAN // sky and holes
        } else {
            20.0 + 3.0 * x as f32
        }
    });
    let photo = Photo::from_range(image, range)?;
    let prepared = photo::prepare(
        &photo,
        &PrepareOptions::for_photo(&photo),
        headless.renderer()?,
    )?;
    let fog = FogOptions::visibility(150.0)?;
    Ok(photo::fog(headless.renderer()?, &photo, &prepared, &fog)?
        .rendered
        .image)
}

#[test]
fn a_forked_child_renders_what_its_parent_renders() {
    if std::env::var_os(ROLE).is_none() {
        let _gl = common::gl_lock();
        let out = Command::new(std::env::current_exe().unwrap())
            .args([NAME, "--exact", "--test-threads=1", "--nocapture"])
            .env(ROLE, "1")
            .output()
            .unwrap();
        let log = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{log}{}", common::stderr(&out));
        assert!(
            log.contains("1 passed"),
            "the forking test did not run: {log}"
        );
        return;
    }
    let mut headless = common::headless();
    let parent = fog_photo(&mut headless).unwrap();
    // SAFETY: the child calls only brume and _exit; no other thread of this process holds
    // a lock of this test's (it runs alone).
    let pid = unsafe { fork() };
    assert!(pid >= 0, "fork failed");
    if pid == 0 {
        let code = match Headless::new(None).and_then(|mut h| fog_photo(&mut h)) {
            Ok(child) if child.as_slice() == parent.as_slice() => 0,
            Ok(_) => 1,
            Err(e) => {
                eprintln!("the child's render failed: {e}");
                2
            }
        };
        // SAFETY: ends the child without running the test harness's exit path.
        unsafe { _exit(code) }
    }
    let status = wait_for(pid, Duration::from_secs(120));
    assert_eq!(
        status,
        Some(0),
        "the child (0: the parent's image, 1: another image, 2: an error, None: hung)"
    );
    // The parent's context still works after the fork.
    assert_eq!(
        fog_photo(&mut headless).unwrap().as_slice(),
        parent.as_slice()
    );
}

/// The exit code of child `pid`, or `None` (the child killed) if it has not ended within
/// `limit`.
fn wait_for(pid: i32, limit: Duration) -> Option<i32> {
    let start = Instant::now();
    let mut status = 0;
    while start.elapsed() < limit {
        // SAFETY: `pid` is this process's child; `status` is a valid out-pointer.
        if unsafe { waitpid(pid, &mut status, WNOHANG) } == pid {
            return (status & 0x7f == 0).then_some((status >> 8) & 0xff);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    // SAFETY: as above; the child is killed and reaped.
    unsafe {
        kill(pid, SIGKILL);
        waitpid(pid, &mut status, 0);
    }
    None
}
