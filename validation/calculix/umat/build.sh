#!/bin/sh
# build.sh: CalculiX 2.20 (Debian bookworm's calculix-ccx 2.20-1 source) linked with
# indentify's user material umat_user.f, as ./ccx_hencky, and the material-point checks
# test_point.f, run at the end. See README.md.
#
#   validation/calculix/umat/build.sh [SRC]
#
# SRC: ccx's source folder (default /work/ccx-src/calculix-ccx-2.20/ccx_2.20/src). Get it
# with a deb-src line for bookworm and `apt-get source calculix-ccx`; build dependencies:
# `apt-get install gfortran libspooles-dev libarpack2-dev liblapack-dev`. The archive
# ccx_2.20.a is built there once (Debian's flags, about 10 min on 2 cores); our
# umat_user.o is linked before it, so the linker never takes the stock umat_user.o out
# of the archive (the source tree is not modified).
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
SRC=${1:-/work/ccx-src/calculix-ccx-2.20/ccx_2.20/src}
CFLAGS='-O2 -w -I/usr/include/spooles -DARCH="Linux" -DSPOOLES -DARPACK -DMATRIXSTORAGE -DUSE_MT=1'
FFLAGS='-O2 -w -fallow-argument-mismatch'
if [ ! -f "$SRC/ccx_2.20.a" ] || [ ! -f "$SRC/ccx_2.20.o" ]; then
    (cd "$SRC" && make ccx_2.20.a ccx_2.20.o CFLAGS="$CFLAGS" FFLAGS="$FFLAGS")
fi
BUILD=$(mktemp -d)
trap 'rm -rf "$BUILD"' EXIT
gfortran -O2 -Wall -Wno-unused-dummy-argument -c "$HERE/umat_user.f" -o "$BUILD/umat_user.o"
gfortran -O2 -o "$HERE/ccx_hencky" "$SRC/ccx_2.20.o" "$BUILD/umat_user.o" "$SRC/ccx_2.20.a" \
    -lspooles -lpthread -larpack -llapack -lblas -lm -lc -fopenmp
gfortran -O2 -Wall -Wno-unused-dummy-argument -o "$BUILD/test_point" \
    "$HERE/test_point.f" "$BUILD/umat_user.o"
"$BUILD/test_point"
echo "built $HERE/ccx_hencky"
