#!/usr/bin/env bash
# Installs what brume needs at run time and in CI, if it is missing: Mesa's EGL and
# OpenGL ES (llvmpipe works headless, no GPU or display needed), the X client libraries
# `brume view` loads at run time and Xvfb for its window tests, `script` (bsdutils: the
# tests run `brume` on a pseudo-terminal to see its spinner), the rustfmt/clippy
# components and the aarch64-linux-android target (for the Android app's check). Safe to
# run again: it installs nothing that is already there.
set -euo pipefail

packages=(libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri
    libx11-6 libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0 xvfb xauth
    bsdutils)

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done

if ((${#missing[@]})); then
    echo "setup: installing ${missing[*]}"
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null || { echo "setup: need root or sudo to install ${missing[*]}" >&2; exit 1; }
        sudo="sudo"
    fi
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
    echo "setup: Mesa EGL/GLES, X libraries, Xvfb and script present"
fi

# The Android app's target: CI checks the workspace for it (no NDK needed to check).
android_target=aarch64-linux-android
if ! rustup target list --installed | grep -qx "$android_target"; then
    echo "setup: adding the $android_target target"
    rustup target add "$android_target"
fi

for component in rustfmt clippy; do
    if ! cargo "${component/rustfmt/fmt}" --version >/dev/null 2>&1; then
        echo "setup: adding the $component component"
        rustup component add "$component"
    fi
done
