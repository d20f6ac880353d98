#!/usr/bin/env bash
# cli/safety2: the second safety probe's classes (issue "safety, second pass"), one check per class
# through the executables, each asserting the exit code, the message (printed) and, by sha256,
# that every file a user put there is unchanged. Class 1 (the pipeline's stage folders) and 9 (its
# step cache) are in pipeline/end_to_end; value-level checkpoint mutation is in fuzz/long.
# Disk full (a tmpfs) and PID namespaces (unshare) need root: without it they are skipped, saying so.
# Usage: safety2.sh BUILD_DIR
set -u
B=$(cd "$1" && pwd)
. "$(dirname "$0")/lib.sh"
SOLVE=$B/solver/tactus-solve MESH=$B/mesher/tactus-mesh SEG=$B/segment/tactus-segment POST=$B/postproc/tactus-post
SAMPLE=$B/data_samples/tactus-sample-mesh PHANTOM=$B/data_samples/tactus-phantom
PY=/usr/bin/python3  # Debian's, with python3-pydicom and python3-nibabel (scripts/setup.sh)
cd "$T" || exit 1

cube_case .
# A run of a few seconds that checkpoints every 10,000 steps.
sed 's/end_time = 0.05/end_time = 0.25\ntime_step = 1e-6\ncheckpoint_interval = 0.01/' s.toml > slow.toml
# scenario VARIANT 'sed script': s.toml edited.
variant() { sed "$2" s.toml > "$1"; }
wait_for() {  # wait_for GLOB: up to 20 s for a path matching GLOB
  local i
  for i in $(seq 200); do compgen -G "$1" > /dev/null && return 0; sleep 0.1; done
  return 1
}
echo "my notes" > notes.txt
user_sum=$(sha256sum notes.txt)

# --- 2, 12. Two runs, one output: the later refuses while the first holds its lock; in separate
# PID namespaces (both pid 1) too, and a killed pid-1 run's checkpoints survive the next pid-1 run.
"$SOLVE" slow.toml -o two -q &
first=$!
wait_for "two.partial-*/.tactus-lock" || bad "the first run made no staging folder"
expect 1 "is writing this output right now" -- "$SOLVE" s.toml -o two
wait $first || bad "the first of two concurrent runs failed"
[ -f two/run.json ] || bad "the first of two concurrent runs published nothing"
if [ "$(id -u)" = 0 ] && unshare --pid --fork true 2> /dev/null; then
  unshare --pid --fork "$SOLVE" slow.toml -o ns -q 2> /dev/null &
  outer=$!
  wait_for "ns.partial-1-*/checkpoints/checkpoint_*.h5" || bad "the namespaced run wrote no checkpoint"
  expect 1 "is writing this output right now" -- unshare --pid --fork "$SOLVE" s.toml -o ns
  kill -9 "$(pgrep -P $outer)"
  wait $outer 2> /dev/null
  staging=$(ls -d ns.partial-1-*)
  ckpt_sum=$(cd "$staging" && sha256sum checkpoints/*)
  unshare --pid --fork "$SOLVE" s.toml -o ns -q || bad "a pid-1 run after a killed pid-1 run failed"
  [ "$(cd "$staging" 2> /dev/null && sha256sum checkpoints/*)" = "$ckpt_sum" ] || bad "the killed pid-1 run's checkpoints were lost"
  echo "ok: the killed pid-1 run's checkpoints survive in $staging"
else
  echo "skipped: PID namespaces (needs root and unshare --pid)"
fi

# --- 3. Replacing an output folder: another tool's folder, a user's empty folder, a hand-written
# manifest claiming the user's file.
"$MESH" box --size 0.02 0.02 0.02 --element-size 0.005 -o meshdir -q
mesh_sum=$(sums meshdir)
expect 1 "holds the output of tactus-mesh, not of tactus-solve" -- "$SOLVE" s.toml -o meshdir
[ "$(sums meshdir)" = "$mesh_sum" ] || bad "the mesh folder changed"
"$SOLVE" s.toml -o res -q
mkdir res/my_empty_folder && cp notes.txt res/ && ln -s ../notes.txt res/my_link
"$SOLVE" s.toml -o res -q --end-time 0.04 || bad "replacing its own output with a user's files in it failed"
[ -d res/my_empty_folder ] && [ -L res/my_link ] && [ "$(cd res && sha256sum notes.txt)" = "$user_sum" ] || bad "a user's entry in res/ was lost"
grep -q '"end_time": 0.04' res/run.json || bad "res/ was not replaced"
mkdir forged && cp notes.txt forged/  # a manifest copied by hand, now also claiming the user's notes.txt
$PY -c 'import json, sys; m = json.load(open("res/.tactus-output.json")); m["files"]["notes.txt"] = {"hash": "0123456789abcdef", "size": 9}; json.dump(m, open("forged/.tactus-output.json", "w"))'
expect 1 "notes.txt" -- "$SOLVE" s.toml -o forged
[ "$(cd forged && sha256sum notes.txt)" = "$user_sum" ] || bad "a hand-written manifest got the user's file replaced"

# --- 4. Disk full on a 2 MB tmpfs: mesh, sample mesh and a solve that fills it half way (checkpoints
# kept, told how to continue, continued after space is freed).
if [ "$(id -u)" = 0 ] && mkdir small && mount -t tmpfs -o size=2m tmpfs small 2> /dev/null; then
  cleanup_hooks+=("umount '$T/small'")
  cp notes.txt small/
  expect 1 "no space left on device" -- "$MESH" box --size 0.05 0.05 0.02 --element-size 0.002 -o small/m
  expect 1 "no space left on device" -- "$SAMPLE" --size 0.02 0.02 0.02 --cells 40 40 40 -o small/c.msh
  [ -z "$(ls small | grep -v notes.txt)" ] || bad "a failed write left output behind: $(ls small)"
  umount small && mount -t tmpfs -o size=6m tmpfs small && cp notes.txt small/
  "$SOLVE" slow.toml -o small/r -q 2> full.err &
  run=$!
  wait_for "small/r.partial-*/checkpoints/checkpoint_*.h5" || bad "the solve on the tmpfs wrote no checkpoint"
  dd if=/dev/zero of=small/filler bs=64k 2> /dev/null
  wait $run
  rc=$?
  [ $rc = 1 ] && grep -q "no space left on device" full.err && grep -q "tactus-solve --restart .*small/r continues" full.err \
    || bad "solve on a full disk: rc $rc: $(cat full.err)"
  echo "ok (rc $rc): $(tail -1 full.err)"
  [ ! -e small/r ] || bad "a solve that ran out of space published small/r"
  rm small/filler
  "$SOLVE" --restart small/r -q || bad "--restart after freeing space failed"
  [ -f small/r/run.json ] && grep -q '"status": "completed"' small/r/run.json || bad "the continued run did not complete"
  [ "$(cd small && sha256sum notes.txt)" = "$user_sum" ] || bad "notes.txt on the full disk changed"
else
  echo "skipped: disk full (needs root to mount a small tmpfs)"
fi

# --- 5. Output paths normalised before any work; a commit killed half way finished by the next run.
"$SOLVE" s.toml -o trailing/ -q && [ -f trailing/run.json ] || bad "-o trailing/ did not publish trailing"
mkdir real && ln -s real link
expect 1 "tactus does not write through links" -- "$SOLVE" s.toml -o link/
[ -z "$(ls real)" ] || bad "-o link/ wrote into the link's target"
mkdir a && "$SOLVE" s.toml -o a/missing/../b -q && [ -f a/b/run.json ] || bad "-o a/missing/../b did not publish a/b"
for at in commit:complete commit:swapped; do
  TACTUS_KILL_AT=$at "$SOLVE" s.toml -o res -q --end-time 0.03 2> /dev/null
  rc=$?
  [ $rc = 137 ] || bad "TACTUS_KILL_AT=$at: rc $rc (want 137, killed)"
  expect 0 "" -- "$SOLVE" s.toml -o res --end-time 0.02
  grep -q '"end_time": 0.02' res/run.json && [ "$(cd res && sha256sum notes.txt)" = "$user_sum" ] && [ -d res/my_empty_folder ] \
    || bad "after a commit killed at $at: res/ is not the new run with the user's files"
  [ -z "$(ls -d res.partial-* 2> /dev/null)" ] || bad "after a commit killed at $at: $(ls -d res.partial-*) left"
done

# --- 6. Special files: refused by type, naming the path, never read (each under a 20 s timeout).
mkfifo pipe
special() {  # special PATH KIND -- command...: refused, naming the path and what it is
  local path=$1 kind=$2
  shift 3
  expect 1 "$kind" -- timeout 20 "$@"
  grep -qF "$path" <<<"$(timeout 20 "$@" 2>&1 > /dev/null)" || bad "the message does not name $path"
}
special pipe "FIFO" -- "$MESH" fibres pipe -o f.vtu
special /dev/zero "character device" -- "$MESH" fibres /dev/zero -o f.vtu
variant fifo_mesh.toml 's|mesh = "cube.msh"|mesh = "pipe"|'
special pipe "FIFO" -- "$SOLVE" fifo_mesh.toml -o out
variant zero_fibres.toml 's|mesh = "cube.msh"|mesh = "cube.msh"\nfibres = "/dev/zero"|'
special /dev/zero "character device" -- "$SOLVE" zero_fibres.toml -o out
"$PHANTOM" --voxel-mm 6 --slice-mm 6 -o stack -q
cp -r stack stack_fifo && rm stack_fifo/slice_0003.png && mkfifo stack_fifo/slice_0003.png
special slice_0003.png "FIFO" -- "$SEG" stack_fifo -o seg
cp -r stack stack_dir && rm stack_dir/slice_0003.png && mkdir stack_dir/slice_0003.png
special slice_0003.png "a folder" -- "$SEG" stack_dir -o seg
ln -s /dev/urandom volume.nii
special volume.nii "character device" -- "$SEG" volume.nii -o seg
[ ! -e seg ] && [ ! -e out ] && [ ! -e f.vtu ] || bad "a refused special file left output behind"

# --- 7. Runaway parameters: bounded by what they can mean, refused at once and within 2 GB.
variant tiny_ckpt.toml 's/end_time = 0.05/end_time = 0.05\ncheckpoint_interval = 1e-300/'
expect 1 "run.checkpoint_interval" -- timeout 20 "$SOLVE" tiny_ckpt.toml -o out
expect 1 "--denoise" -- timeout 20 "$SEG" stack -o seg --denoise 1e6
expect 1 "--edge-voxels" -- timeout 20 "$SEG" stack -o seg --edge-voxels 0.01
$PY - <<'PY'
import struct
h = bytearray(348)
struct.pack_into("<i", h, 0, 348)
struct.pack_into("<8h", h, 40, 3, 1000, 1000, 700, 1, 1, 1, 1)  # 7e8 voxels declared
struct.pack_into("<hh", h, 70, 4, 16)  # int16
struct.pack_into("<8f", h, 76, 1, 1, 1, 1, 1, 1, 1, 1)
struct.pack_into("<f", h, 108, 352.0)
struct.pack_into("<f", h, 112, 1.0)
h[344:348] = b"n+1\0"
open("huge.nii", "wb").write(bytes(h) + b"\0\0\0\0")
PY
expect 1 "expected 1400000000 bytes of voxels after byte 352, found 0 (truncated)" -- bash -c "ulimit -v 2000000; timeout 20 '$SEG' huge.nii -o seg"
[ ! -e seg ] && [ ! -e out ] || bad "a refused runaway parameter left output behind"

# --- 10. Accepted but meaningless: refused, or warned where legal but suspicious.
expect 1 "--angle: expected a finite number" -- "$MESH" fibres cube.msh --angle nan -o f.vtu
expect 1 "--inclusion: expected a finite number" -- "$SAMPLE" --inclusion 0 0 0 nan 1 1 -o x.msh
expect 1 "--denoise" -- "$SEG" stack -o seg --denoise -1
variant threads.toml 's/\[run\]/[run]\nthreads = 2.5/'
expect 1 "run.threads" -- "$SOLVE" threads.toml -o out
variant every.toml 's/\[run\]/[run]\nhistory_every = 0.5/'
expect 1 "run.history_every" -- "$SOLVE" every.toml -o out
variant rigid.toml 's/initial_velocity = \[0.1, 0, 0\]/rigid_velocity = [0.1, 0, 0]/'
expect 1 "rigid_velocity" -- "$SOLVE" rigid.toml -o out
cat s.toml > fixed_moving.toml && cat >> fixed_moving.toml <<'TOML'
[[boundary]]
body = "cube"
group = "xmin"
type = "fixed"
[[boundary]]
body = "cube"
group = "xmin"
type = "velocity"
velocity = [0.1, 0, 0]
TOML
expect 1 "is fixed in x by boundary[0] and velocity by this one" -- "$SOLVE" fixed_moving.toml -o out
"$PHANTOM" --voxel-mm 6 --slice-mm 6 --format dicom -o dicom -q
$PY - <<'PY'
import pydicom, glob, shutil
shutil.copytree("dicom", "dicom_short")
f = sorted(glob.glob("dicom_short/*.dcm"))[3]
d = pydicom.dcmread(f)
d.PixelData = d.PixelData[:100]  # 100 bytes where rows x columns x 2 are needed
d.save_as(f)
shutil.copytree("dicom", "dicom_mr")
for f in glob.glob("dicom_mr/*.dcm"):
    d = pydicom.dcmread(f)
    d.Modality = "MR"
    d.save_as(f)
import nibabel, numpy as np
img = nibabel.Nifti1Image(np.zeros((8, 8, 8), np.int16), np.diag([3.0, 3.0, 3.0, 1.0]))
img.header.set_qform(np.diag([3.0, 3.0, 3.0, 1.0]), code=1)
img.header.set_sform(None, code=0)
nibabel.save(img, "skewed.nii")
import struct
raw = bytearray(open("skewed.nii", "rb").read())
struct.pack_into("<3f", raw, 256, 0.9, 0.9, 0.9)  # quatern_b, c, d: not a unit quaternion (nibabel refuses to write one)
open("skewed.nii", "wb").write(raw)
PY
expect 1 "(7FE0,0010) PixelData" -- "$SEG" dicom_short -o seg
expect 0 "Modality is MR, not CT" -- "$SEG" dicom_mr -o seg_mr --no-surfaces
expect 1 "quatern_b/c/d" -- "$SEG" skewed.nii -o seg
# tactus-post: a state of another model, a history without its header, a run that failed.
"$SAMPLE" --size 0.02 0.02 0.02 --cells 3 3 3 -o small_cube.msh -q
sed 's/cube.msh/small_cube.msh/' s.toml > other.toml && "$SOLVE" other.toml -o other -q
cp -r res mixed && rm -f mixed/.tactus-output.json && cp other/results/state_0000.vtu mixed/results/state_0000.vtu
expect 1 "state_0000.vtu" -- "$POST" mixed -o rep --no-pictures
cp -r res headless && rm -f headless/.tactus-output.json && sed -i 1d headless/history.csv
expect 1 "history.csv" -- "$POST" headless -o rep --no-pictures
[ ! -e rep ] || bad "tactus-post published a report of an inconsistent result folder"
variant crushed.toml 's/initial_velocity = \[0.1, 0, 0\]/initial_velocity = [1e5, 0, 0]\n[[boundary]]\nbody = "cube"\ngroup = "xmin"\ntype = "fixed"/'
expect 3 "inverted element" -- "$SOLVE" crushed.toml -o crushed
expect 0 "" -- "$POST" crushed -o crushed_rep --no-pictures
grep -q "Run failed: inverted element" crushed_rep/summary.md || bad "the report of a failed run does not say it failed"

# --- 11. Signals late in tactus-mesh and tactus-post: exit 128+signal, nothing published. The
# signal is sent at several moments across the run; each either lets it finish (exit 0, complete)
# or stops it (143, nothing at the output path).
# (A first run measures how long the work takes; the signals come at 60 to 99 % of it.)
for tool in mesh post; do
  run_tool() {
    if [ $tool = mesh ]; then exec "$MESH" box --size 0.05 0.05 0.02 --element-size 0.0015 -o sig_out -q; else exec "$POST" res -o sig_out -q; fi
  }
  rm -rf sig_out
  start=$(date +%s.%N)
  (run_tool 2> /dev/null) || bad "tactus-$tool failed without a signal"
  duration=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }')
  for fraction in 0.6 0.85 0.95 0.99; do
    rm -rf sig_out
    run_tool 2> sig.err &
    pid=$!
    sleep "$(awk -v d="$duration" -v f=$fraction 'BEGIN { printf "%.3f", d * f }')"
    kill -TERM $pid 2> /dev/null
    wait $pid
    rc=$?
    if [ $rc = 143 ]; then
      [ ! -e sig_out ] && [ -z "$(ls -d sig_out.partial-* 2> /dev/null)" ] || bad "tactus-$tool stopped by SIGTERM left output behind"
      grep -q "interrupted (SIGTERM)" sig.err || bad "tactus-$tool SIGTERM message: $(cat sig.err)"
    elif [ $rc = 0 ]; then
      [ -f sig_out/.tactus-output.json ] || bad "tactus-$tool finished but sig_out is incomplete"
    else
      bad "tactus-$tool with SIGTERM at $fraction of its run: rc $rc: $(cat sig.err)"
    fi
    echo "ok: tactus-$tool, SIGTERM at $fraction of its ${duration}s run: rc $rc"
  done
done

[ "$(sha256sum notes.txt)" = "$user_sum" ] || bad "notes.txt changed"
[ $fail = 0 ] && echo "all second-pass safety checks passed"
exit $fail
