#!/usr/bin/env bash
# The README's test command: installs what the test suite needs and is missing, then runs
# `cargo test --all-features` and the Python package's pytest suite. With arguments, only
# `cargo test --all-features ARGS` after the set-up (`./test.sh --test cli`); `--setup` and
# `--python` run just that step.
#
# Needs: a Rust toolchain, ../shared beside the repository, and a Debian-like system (apt-get,
# as root or through sudo) for what is missing:
# - chromium + chromium-driver: the viewer's browser tests (tests/web/browser.rs) drive
#   headless Chromium through chromedriver; they fail (never skip) without them.
# - iproute2 (`ip`): tests/ros2/netns.rs puts the supervisor and robots in network
#   namespaces.
# - python3 + venv: a venv at target/venv-ros2 with the PyPI packages cyclonedds==11.0.1
#   (tests/ros2/interop.rs, tests/ros2/python_robot.rs), mcap==1.6.0 and
#   mcap-ros2-support==0.6.0 (tests/ros2/runs_recorded_to_mcap.rs) and stormpy==2.0.0 (Storm, for
#   tests/analysis/storm_cross_check.rs and the docs' Storm snippet; an x86_64 manylinux
#   wheel for CPython 3.11) and eclipse-zenoh==1.10.2 (tests/zenoh: a subscriber and a robot
#   on Zenoh's own Python API, tests/zenoh/*.py).
# - the Python package (python/, docs/python.md): built by pip (maturin) into a venv at
#   target/venv-py with pytest and matplotlib, its suite run against the plan-runner that
#   `cargo test` built.
# What is present is left alone, so a second run starts the tests at once.
set -euo pipefail
cd "$(dirname "$0")"

if [ ! -d ../shared/fixtures ]; then
    echo "error: ../shared (fixtures) must sit beside the repository" >&2
    exit 1
fi

# apt-get as root, or through sudo.
apt_install() {
    local sudo=()
    if [ "$(id -u)" -ne 0 ]; then
        if ! command -v sudo >/dev/null 2>&1; then
            echo "error: $* missing and not root (no sudo): install them: apt-get install $*" >&2
            exit 1
        fi
        sudo=(sudo)
    fi
    echo "== installing $*"
    "${sudo[@]}" apt-get update -q
    DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -q "$@"
}

# The set-up: what the suite needs and is missing.
setup() {
    missing=()
    command -v chromium >/dev/null 2>&1 || missing+=(chromium)
    command -v chromedriver >/dev/null 2>&1 || missing+=(chromium-driver)
    command -v ip >/dev/null 2>&1 || missing+=(iproute2)
    if ! python3 -c 'import venv, ensurepip' >/dev/null 2>&1; then
        missing+=(python3 python3-venv)
    fi
    if [ "${#missing[@]}" -gt 0 ]; then
        apt_install "${missing[@]}"
    fi

    venv=target/venv-ros2
    if [ ! -x "$venv/bin/python" ]; then
        echo "== Python venv $venv"
        rm -rf "$venv"
        python3 -m venv "$venv"
    fi
    # pip answers "already satisfied" without the network when the versions are there.
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check \
        cyclonedds==11.0.1 stormpy==2.0.0 mcap==1.6.0 mcap-ros2-support==0.6.0 \
        eclipse-zenoh==1.10.2
}

# The Python package's suite, against the plan-runner `cargo test` built.
python_tests() {
    echo "== Python package: pip install ./python, pytest"
    target="${CARGO_TARGET_DIR:-$PWD/target}"
    if [ ! -x target/venv-py/bin/python ]; then
        python3 -m venv target/venv-py
    fi
    CARGO_TARGET_DIR="$target" \
        target/venv-py/bin/pip install --quiet --disable-pip-version-check ./python pytest matplotlib
    GSPN_PLAN_RUNNER="$target/debug/plan-runner" target/venv-py/bin/python -m pytest -q python/tests
}

# `--setup` and `--python` run one step each (`.ci/run` runs the three steps one by one,
# so its log shows `cargo test` as its own command).
case "${1:-}" in
--setup)
    setup
    exit 0
    ;;
--python)
    python_tests
    exit 0
    ;;
esac
setup
echo "== cargo test --all-features $*"
cargo test --all-features "$@"
if [ "$#" -gt 0 ]; then
    exit 0
fi
python_tests
