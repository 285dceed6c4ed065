#!/usr/bin/env bash
# patchscan-mpi against patchscan render --threads 1: the same image, bit for bit, under
# mpirun with 2 and 4 processes (more than this machine's cores: --oversubscribe), with
# --threads 1 and (four processes) the default; and its
# faults: a scene that cannot be read, an output that cannot be written, a process that
# fails mid-frame: every process exits with the same non-zero code, one message, no image,
# nothing hangs (each mpirun runs under a timeout).
# Usage: mpi_test.sh CASE PATCHSCAN PATCHSCAN_MPI SURFACES_DIR
set -uo pipefail
case_name=$1 single=$2 multi=$3 surfaces=$4
# As root OpenMPI needs leave to run; in containers its shared-memory transport may not
# use cross-memory attach.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1
# One machine: shared memory between the processes. More processes than cores: a process
# waiting for a message yields its core.
export OMPI_MCA_mpi_yield_when_idle=1 OMPI_MCA_btl=self,vader
# Under AddressSanitizer (the sanitizer stage of CI) OpenMPI's own start-up allocations,
# kept until exit, would be reported as leaks: memory errors are still fatal.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
fail() { echo "FAIL: $*"; exit 1; }
mpi() { local n=$1; shift; timeout 120 mpirun --oversubscribe -n "$n" "$multi" "$@"; }

# The same bytes (PNG) or the same pixels in every channel (EXR with AOVs).
same_image() {
  local n=$1 out=$2; shift 2
  "$single" render "$@" --threads 1 -o "one.$out" --quiet || fail "patchscan render $*"
  mpi "$n" render "$@" --threads 1 -o "many.$out" --quiet || fail "patchscan-mpi -n $n render $*"
  if [ "$out" = png ]; then
    cmp -s one.png many.png || fail "-n $n $*: the PNG differs from patchscan render's"
  else
    idiff -q -fail 0 -warn 0 one.exr many.exr >/dev/null || fail "-n $n $*: the EXR differs from patchscan render's"
  fi
  echo "same image: -n $n $*"
}

case $case_name in
  teapot)
    for n in 2 4; do
      for mode in exact theta; do same_image "$n" png "$surfaces/teapot.bpt" --size 240x180 --mode "$mode"; done
      same_image "$n" png "$surfaces/teapot.bpt" --size 240x180 --mode theta --y-step 1 --aa 3
      same_image "$n" png "$surfaces/teapot.bpt" --size 240x180 --mode tess
    done
    # Each process's threads by default: the node's cores shared among its processes (four
    # processes on two cores: one thread each). Two threads apiece there took over 40 s
    # for this half-second render, all threads busy on too few cores.
    "$single" render "$surfaces/teapot.bpt" --size 240x180 --mode theta --threads 1 -o one.png --quiet ||
      fail "patchscan render"
    timeout 30 mpirun --oversubscribe -n 4 "$multi" render "$surfaces/teapot.bpt" --size 240x180 --mode theta \
      -o many.png --quiet || fail "patchscan-mpi -n 4 with the default --threads: failed or over 30 s"
    cmp -s one.png many.png || fail "-n 4, default --threads: the PNG differs from patchscan render's"
    echo "same image: -n 4, default --threads"
    # An explicit --threads is taken as given; where it oversubscribes the machine a note
    # says so, once.
    timeout 60 mpirun --oversubscribe -n 2 "$multi" render "$surfaces/teapot.bpt" --size 240x180 --mode theta \
      --threads $(( $(nproc) + 1 )) -o many.png --quiet 2>err.txt || fail "patchscan-mpi -n 2 --threads nproc+1: $(cat err.txt)"
    [ "$(grep -c 'note: 2 processes on this machine with --threads' err.txt)" -eq 1 ] ||
      fail "no note of oversubscription: $(cat err.txt)"
    cmp -s one.png many.png || fail "-n 2, --threads nproc+1: the PNG differs from patchscan render's"
    echo "same image and a note: -n 2, --threads $(( $(nproc) + 1 ))" ;;
  rib)
    # Each scene in each direct mode once: exact with 2 processes, θ with 4.
    for scene in quadrics.rib polygons.rib trimmed.rib cages.rib curves.rib shading.rib; do
      same_image 2 exr "$surfaces/$scene" --size 160x100 --aa 2 --mode exact --aov
      same_image 4 exr "$surfaces/$scene" --size 160x100 --aa 2 --mode theta --aov
    done ;;
  cad)
    # A STEP model of Open CASCADE's sample data (occt-misc): its faces' trimmed pieces in the
    # direct modes, Open CASCADE's own mesh in tess mode.
    model=/usr/share/opencascade/data/step/screw.step
    [ -f "$model" ] || { echo "occt-misc is not installed: no CAD model"; exit 0; }
    for mode in exact theta tess; do same_image 3 exr "$model" --size 160x100 --aa 2 --mode "$mode" --aov; done ;;
  frames)
    # Every frame of a production scene (a shadow map, then the picture through it).
    mkdir one many
    (cd one && "$single" render "$surfaces/still_life.rib" --size 240x135 --threads 1 --quiet) || fail "patchscan render"
    (cd many && mpi 3 render "$surfaces/still_life.rib" --size 240x135 --threads 1 --quiet) || fail "patchscan-mpi render"
    cmp -s one/still_life.png many/still_life.png || fail "still_life.png differs"
    echo "same frames: -n 3 still_life.rib" ;;
  faults)
    # A scene that cannot be read: 1, the message once.
    mpi 3 render nothing.rib -o x.png 2>err.txt
    code=$?
    [ $code -eq 1 ] || fail "unreadable scene: exit $code"
    [ "$(grep -c 'nothing.rib: cannot open' err.txt)" -eq 1 ] || fail "unreadable scene: $(cat err.txt)"
    # An output that cannot be written: 3.
    mpi 3 render "$surfaces/teapot.bpt" -o /nonexistent/x.png 2>err.txt
    code=$?
    [ $code -eq 3 ] || fail "unwritable output: exit $code"
    [ "$(grep -c 'x.png: cannot write' err.txt)" -eq 1 ] || fail "unwritable output: $(cat err.txt)"
    # Process 1 fails at row 40 (a fault injected): 70 on every process, no image.
    timeout 120 mpirun --oversubscribe -n 1 "$multi" render "$surfaces/teapot.bpt" -o x.png --size 200x150 : \
      -n 1 env PATCHSCAN_MPI_FAIL_AT_ROW=40 "$multi" render "$surfaces/teapot.bpt" -o x.png --size 200x150 2>err.txt
    code=$?
    [ $code -eq 70 ] || fail "a failing process: exit $code"
    grep -q 'failed: process 1: a fault injected at row 40; no output written' err.txt || fail "a failing process: $(cat err.txt)"
    [ -z "$(ls -A | grep -v err.txt)" ] || fail "files left behind: $(ls -A)"
    echo "faults: exit 1, 3 and 70 on every process, no image" ;;
  *) fail "unknown case $case_name" ;;
esac
