# shellcheck shell=bash
# The cameras of the frame-loop overhead benches (bench/null_overhead.sh,
# bench/instruction_counts.sh), as `aperture bench` flags: each camera model at one pose, and
# the calibrated cameras of issue 11 (same K and OPENCV distortion as
# bench/issue11_calibrated.sh: vertical fov 30°, fy = (H / 2) / tan 15°). Sourced from the
# project root after SIZE (W,H) is set; defines POSE and NULL_CAMERAS ("name:flags" entries)
# and NULL_CAMERA_ORDER (the names in table order).
W=${SIZE%,*}
H=${SIZE#*,}
F=$(python3 -c "import math; print(repr(($H / 2) / math.tan(math.radians(15))))")
K="--intrinsics $F,$F,$((W / 2)),$((H / 2))"
POSE="--eye 0,0.12,0.45 --at 0,0.12,0 --up 0,1,0 --size $SIZE"
NULL_CAMERAS=("perspective:--fov 30"
              "thinlens:--camera thinlens --fov 30 --aperture 0.01 --focus 0.45"
              "equirect:--camera equirect"
              "fisheye:--camera fisheye"
              "calibrated-pinhole:$K --lens-model PINHOLE"
              "calibrated-opencv:$K --lens-model OPENCV --distortion -0.1,0.01,1e-4,-1e-4")
NULL_CAMERA_ORDER="perspective thinlens equirect fisheye calibrated-pinhole calibrated-opencv"
export NULL_CAMERA_ORDER
