#!/usr/bin/env bash
# Builds the Python package's wheels for manylinux (glibc 2.28 and later: Debian 10+,
# Ubuntu 18.10+, RHEL 8+) on x86_64 and aarch64, and its source distribution, so that
# `pip install brume-….whl` needs no Rust toolchain. One wheel per platform serves
# CPython 3.9 and later (PyO3's stable ABI). Cross-compiles with maturin and zig, so no
# manylinux container and no aarch64 machine are needed; maturin checks each wheel's
# symbols against the manylinux_2_28 policy and fails the build if one is newer.
#
# Usage: bash tools/build_wheels.sh [--out DIR] [--arch x86_64|aarch64]... [--no-sdist] [--test]
#   --out DIR     where the wheels go (default: dist/)
#   --arch A      build for A only (repeatable; default: x86_64 and aarch64)
#   --no-sdist    no source distribution
#   --test        install this machine's wheel into a fresh virtual environment (no Rust
#                 in it) and run python/tests against it
#
# Needs python3 with venv and a Rust toolchain (rustup adds the targets); maturin and zig
# come from PyPI into target/wheel-tools/.
set -euo pipefail
cd "$(dirname "$0")/.."

out=dist
arches=()
sdist=1
run_tests=0
while (($#)); do
    case "$1" in
        --out|--arch)
            if (($# < 2)); then
                echo "build_wheels: $1 needs a value (see --help)" >&2
                exit 2
            fi
            if [ "$1" = --out ]; then out=$2; else arches+=("$2"); fi
            shift 2
            ;;
        --no-sdist) sdist=0; shift ;;
        --test) run_tests=1; shift ;;
        -h|--help) awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "$0"; exit 0 ;;
        *) echo "build_wheels: unknown option $1 (see --help)" >&2; exit 2 ;;
    esac
done
((${#arches[@]})) || arches=(x86_64 aarch64)
for arch in "${arches[@]}"; do
    case "$arch" in
        x86_64|aarch64) ;;
        *) echo "build_wheels: --arch $arch: expected x86_64 or aarch64" >&2; exit 2 ;;
    esac
done

# zig pinned to the version these wheels were built and checked with; maturin within 1.x,
# as python/pyproject.toml asks.
tools=target/wheel-tools
if ! "$tools/bin/python" -c "import maturin, ziglang" 2>/dev/null; then
    echo "build_wheels: installing maturin and zig into $tools"
    python3 -m venv "$tools"
    "$tools/bin/pip" install -q "maturin>=1.9,<2" "ziglang==0.13.0"
fi
export PATH="$PWD/$tools/bin:$PATH"

# A target folder of its own: the package is a workspace of its own (its own Cargo.lock
# and features), linked by zig, and its builds would otherwise evict the root's.
export CARGO_TARGET_DIR="$PWD/target/wheels"
for arch in "${arches[@]}"; do
    triple="$arch-unknown-linux-gnu"
    if ! rustup target list --installed | grep -qx "$triple"; then
        echo "build_wheels: adding the $triple target"
        rustup target add "$triple"
    fi
    maturin build --release --zig --compatibility manylinux_2_28 \
        -m python/Cargo.toml --target "$triple" --out "$out"
done
if ((sdist)); then
    maturin sdist -m python/Cargo.toml --out "$out"
fi

if ((run_tests)); then
    host=$(uname -m)
    wheel=$(ls -t "$out"/brume-*-manylinux_2_28_"$host".whl 2>/dev/null | head -n 1)
    if [ -z "$wheel" ]; then
        echo "build_wheels: --test: no $host wheel in $out (add --arch $host)" >&2
        exit 1
    fi
    venv=target/wheel-test
    rm -rf "$venv"
    python3 -m venv "$venv"
    # The wheel with its test extra (pytest, Pillow, albumentations: python/pyproject.toml).
    "$venv/bin/pip" install -q "$wheel[test]"
    echo "build_wheels: python/tests against $wheel"
    "$venv/bin/python" -m pytest -q python/tests
fi
