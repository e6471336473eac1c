#!/usr/bin/env bash
# Install the Debian 12 packages the harness needs, only when some are missing.
# Uses sudo when not root. Safe to run repeatedly.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libdeal.ii-dev libgmsh-dev libceres-dev
  libgtest-dev libbenchmark-dev libfmt-dev nlohmann-json3-dev
  libnanoflann-dev libcli11-dev libsuitesparse-dev
  libboost-dev           # header-only Boost.Graph (the meshes' numbering) and Boost.Math (tissue rsr)
  libssl-dev             # SHA-256 of the case and of the surrogate file (OpenSSL::Crypto)
  libopenblas0-pthread   # fast BLAS for the sparse LUs (MUMPS, UMFPACK) of both models
  libmumps-dev           # MUMPS: the EFG model's direct solver (meshless/solvers/mumps_lu.hpp; also a PETSc dependency)
  openmpi-bin libopenmpi-dev  # mpirun for the distributed FEM reference and its MPI test (deal.II is built on OpenMPI)
  libpetsc-real-dev      # PETSc with hypre and Trilinos ML: the EFG model's AMG-Krylov solve (also a deal.II dependency)
  calculix-ccx           # ccx: the independent FE code of `tissue export` and test_calculix_lung (docs/FEM_REFERENCE.md)
  python3 python3-matplotlib
  clang libclang-rt-14-dev    # libFuzzer: the short fuzzing run of the case and STL readers (build_and_test.sh)
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "[deps] all ${#PACKAGES[@]} Debian packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "[deps] missing packages (${missing[*]}) and not root, and sudo is not available" >&2
    exit 1
  fi
fi
echo "[deps] installing: ${missing[*]}"
$SUDO apt-get update -q
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
