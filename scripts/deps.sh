#!/usr/bin/env bash
# Installs the Debian packages Gabion needs to build and run, if missing
# (Open MPI: `mpirun -np N gabion run CASE`); with --tests also what the tests
# need (Chromium opens the pipeline's report; clang builds the fuzzing
# targets, scripts/fuzz.sh; Slurm and munge run a job array on a one-node
# cluster on localhost, scripts/slurm_local.sh).
set -euo pipefail
pkgs=(g++ cmake make ccache libeigen3-dev libnlopt-cxx-dev libhdf5-dev nlohmann-json3-dev libcli11-dev libgtest-dev zlib1g-dev nettle-dev libcairo2-dev pkg-config fonts-dejavu-core clang-format libopenmpi-dev openmpi-bin)
if [ "${1:-}" = "--tests" ]; then pkgs+=(chromium clang); fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
if [ "${1:-}" = "--tests" ]; then
  # (its own installer: it keeps the packages from starting system daemons)
  # (it needs root; without, the Slurm test says it is skipped, and why)
  "$(dirname "$0")/slurm_local.sh" install || echo "Slurm not installed: the Slurm test will be skipped"
fi
