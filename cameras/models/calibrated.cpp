// The calibrated camera: rays of a COLMAP lens model, posed by a matrix or by eye / at / up.
//
// Raster position (x, y) (pixel (i, j) centre at (j + ½, i + ½)) → the source's pixel
// coordinates (sourcePixelOfRaster) → the lens's exact inverse (Lens::unproject) → a unit
// camera-space direction d (OpenCV axes: x right, y down, z forward) → the world direction
// d.x·U − d.y·V − d.z·W, normalised. Origin e. Pixel centres of a distorted lens read d from
// the sensor's DirectionTable, those of an undistorted pinhole compute it in closed form (a
// vector kernel: cheaper than the table's 25 bytes per ray); other samples compute it. A
// pixel the lens maps no ray to is a miss.
#include "cameras/models/calibrated.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "cameras/lenses/direction_table.h"
#include "cameras/models/camera_models.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "core/util/vector_kernel.h"

namespace aperture {

std::vector<double> rowMajor(const glm::dmat4& m) {
  std::vector<double> v(16);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v[size_t(4 * r + c)] = m[c][r];
  return v;
}

glm::dmat4 matrixOfRowMajor(const std::vector<double>& v) {
  glm::dmat4 m(1.0);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m[c][r] = v.at(size_t(4 * r + c));
  return m;
}

namespace {

PixelCentre parsePixelCentre(const std::string& name) {
  return name == "integer" ? PixelCentre::Integer : PixelCentre::HalfInteger;
}

}  // namespace

CalibratedSensor calibratedSensorOf(const CameraParams& p) {
  if (!p.intrinsics) throw Error("calibrated camera: --intrinsics fx,fy,cx,cy is required");
  const LensModelInfo& model = findLensModel(p.lensModel);
  const std::vector<double>& k = *p.intrinsics;
  const double fx = k[0], fy = k[1], cx = k[2], cy = k[3];
  std::vector<double> params;
  if (model.ownMap()) {
    // Its parameters are all "distortion" (EQUIRECTANGULAR: w, h); the intrinsics must be the
    // linear part of its map, as Lens reports them (and calibratedCameraParams writes them).
    if (!p.distortion)
      throw Error(cat("--distortion: camera model ", model.name, " needs its parameters (",
                      join(model.paramNames, ","), ")"));
    const Lens lens(model.id, *p.distortion);
    const double want[4] = {lens.fx(), lens.fy(), lens.cx(), lens.cy()};
    for (int i = 0; i < 4; ++i)
      if (!(std::abs(k[size_t(i)] - want[i]) <= 1e-9 * std::abs(want[i])))
        throw Error(cat("--intrinsics: camera model ", model.name, " with ",
                        join(model.paramNames, ","), " = ",
                        join(*p.distortion, ",", [](double d) { return cat(d); }),
                        " has fx,fy,cx,cy = ", want[0], ",", want[1], ",", want[2], ",", want[3],
                        "; got ", fx, ",", fy, ",", cx, ",", cy));
    CalibratedSensor s;
    s.width = p.width;
    s.height = p.height;
    s.lens = lens;
    s.pixelCentre = parsePixelCentre(p.pixelCentre);
    return s;
  }
  if (model.singleFocal()) {
    if (fx != fy)
      throw Error(cat("--intrinsics: camera model ", model.name,
                      " has one focal length, but fx = ", fx, " and fy = ", fy, " differ"));
    params = {fx, cx, cy};
  } else {
    params = {fx, fy, cx, cy};
  }
  const size_t takes = model.paramNames.size() - params.size();
  const std::vector<double> dist = p.distortion.value_or(std::vector<double>(takes, 0.0));
  if (dist.size() != takes)
    throw Error(cat(
        "--distortion: camera model ", model.name, " takes ", takes, " coefficient",
        takes == 1 ? "" : "s", " (",
        join(std::vector<const char*>(model.paramNames.end() - long(takes), model.paramNames.end()),
             ","),
        "), got ", dist.size()));
  params.insert(params.end(), dist.begin(), dist.end());
  CalibratedSensor s;
  s.width = p.width;
  s.height = p.height;
  s.lens = Lens(model.id, params);
  s.pixelCentre = parsePixelCentre(p.pixelCentre);
  return s;
}

CameraFrame frameOfWorldToCamera(const glm::dmat4& m) {
  // GLM m[column][row]: row r of R is (m[0][r], m[1][r], m[2][r]); t is column 3.
  const glm::dvec3 x(m[0][0], m[1][0], m[2][0]), y(m[0][1], m[1][1], m[2][1]),
      z(m[0][2], m[1][2], m[2][2]);
  const glm::dvec3 t(m[3][0], m[3][1], m[3][2]);
  CameraFrame f;
  f.e = -(t.x * x + t.y * y + t.z * z);  // −Rᵀt
  f.u = x;
  f.v = -y;
  f.w = -z;
  return f;
}

namespace {

/// OpenCV camera space (x right, y down, z forwards) from the space of frame U, V, W about
/// `eye`: rows U, −V, −W, translated by −R·eye.
glm::dmat4 openCvCameraFromFrame(const glm::dvec3& u, const glm::dvec3& v, const glm::dvec3& w,
                                 const glm::dvec3& eye) {
  glm::dmat4 m(1.0);  // GLM: m[column][row]
  const glm::dvec3 rows[3] = {u, -v, -w};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m[c][r] = rows[r][c];
    m[3][r] = -glm::dot(rows[r], eye);
  }
  return m;
}

}  // namespace

glm::dmat4 calibratedWorldToCamera(const CameraParams& p) {
  const AxisConvention axes = parseAxisConvention(p.convention);
  if (p.worldToCamera)
    return worldToCameraOpenCV(matrixOfRowMajor(*p.worldToCamera), axes, false,
                               "--world-to-camera");
  if (p.cameraToWorld)
    return worldToCameraOpenCV(matrixOfRowMajor(*p.cameraToWorld), axes, true, "--camera-to-world");
  const CameraFrame f = frameFromParams(p);
  return openCvCameraFromFrame(f.u, f.v, f.w, f.e);
}

namespace {

/// The frame of the pose matrix when one is given, else of eye / at / dir / up.
CameraFrame poseFrame(const CameraParams& p) {
  if (p.worldToCamera || p.cameraToWorld) return frameOfWorldToCamera(calibratedWorldToCamera(p));
  return frameFromParams(p);
}

}  // namespace

CameraParams calibratedCameraParams(const CalibratedSensor& sensor,
                                    const glm::dmat4& worldToCameraCv) {
  CameraParams p;
  p.type = "calibrated";
  p.width = sensor.width;
  p.height = sensor.height;
  const Lens& lens = sensor.lens;
  p.lensModel = lens.info().name;
  p.intrinsics = std::vector<double>{lens.fx(), lens.fy(), lens.cx(), lens.cy()};
  const std::vector<double> dist = lens.distortion();
  if (!dist.empty()) p.distortion = dist;
  p.pixelCentre = pixelCentreName(sensor.pixelCentre);
  p.worldToCamera = rowMajor(worldToCameraCv);
  p.convention = axisConventionName(AxisConvention::OpenCV);
  return p;
}

std::optional<CalibratedView> calibratedViewOf(const CameraDescription& c) {
  // OpenEXR's camera space (x right, y up, z forward) to OpenCV's: y flips.
  glm::dmat4 flipY(1.0);
  flipY[1][1] = -1.0;
  CalibratedView view;
  view.worldToCamera = flipY * c.cameraFromWorld;
  view.sensor.width = c.width;
  view.sensor.height = c.height;
  if (c.lens) {
    view.sensor.lens = Lens(findLensModel(c.lens->model).id, c.lens->params);
    view.sensor.pixelCentre = parsePixelCentre(c.lens->pixelCentre);
    return view;
  }
  if (c.type != "perspective" || !c.ndcFromWorld) return std::nullopt;
  // The window's centre is (sx·vw, sy·vh) / d on the plane z = 1 (screenWindowCenter), so the
  // principal point, raster ((½ − sx)·W, (½ + sy)·H), follows from it (ImageWindow).
  const double fx = c.width * c.d / c.vw, fy = c.height * c.d / c.vh;
  const double px = (0.5 - c.screenWindowCenter.x * c.d / c.vw) * c.width;
  const double py = (0.5 + c.screenWindowCenter.y * c.d / c.vh) * c.height;
  view.sensor.lens = Lens(LensModelId::Pinhole, {fx, fy, px, py});
  view.sensor.pixelCentre = PixelCentre::HalfInteger;
  return view;
}

// An undistorted pinhole's directions cost less to compute than to read from memory.
bool readsDirectionTable(const Lens& lens) { return lens.distorted(); }

uint64_t directionTableBytes(const std::vector<CameraParams>& cameras) {
  std::vector<CalibratedSensor> sensors;
  for (const CameraParams& p : cameras) {
    if (p.type != "calibrated") continue;
    CalibratedSensor sensor = calibratedSensorOf(p);
    if (readsDirectionTable(sensor.lens)) sensors.push_back(std::move(sensor));
  }
  return uint64_t(DirectionTable::peakBytes(sensors));
}

namespace {

/// What the pixel-centre kernels need of a calibrated camera: its frame, render-space eye and
/// image size.
struct CalibratedFrame {
  glm::dvec3 u, v, w, eye;
  int width, height;
};

/// World direction of camera-space (OpenCV axes) direction (cx, cy, cz), rounded to float:
/// (cx·U − cy·V) − cz·W normalised with one reciprocal, as CalibratedCamera::worldDirection
/// (which the scalar path calls), term by term.
inline void worldDirectionLane(const CalibratedFrame& f, double cx, double cy, double cz, float& dx,
                               float& dy, float& dz) {
  const double gx = (cx * f.u.x - cy * f.v.x) - cz * f.w.x;
  const double gy = (cx * f.u.y - cy * f.v.y) - cz * f.w.y;
  const double gz = (cx * f.u.z - cy * f.v.z) - cz * f.w.z;
  const double inv = 1.0 / std::sqrt((gx * gx + gy * gy) + gz * gz);
  dx = float(gx * inv);
  dy = float(gy * inv);
  dz = float(gz * inv);
}

/// A kBW x kBH block of pixel centres inside the image from the direction table (the frame
/// loop's blocks lie on the table's 4 x 4 grid; the caller checks), rotated. Each block row is
/// kBW contiguous entries of one table block; a block as wide as the table's is kLanes
/// contiguous entries in lane order, read by one lane loop. The two loops keep their own
/// copies of the lane's two lines: a shared lambda made the 16-wide kernel 13 % slower.
template <int kBW, int kBH>
void tableCentres(const CalibratedFrame& f, const DirectionTable& table, int x0, int y0,
                  RayLanes& out, int* valid) {
  constexpr int kLanes = kBW * kBH;
  const double *tx = table.x(), *ty = table.y(), *tz = table.z();
  const unsigned char* tv = table.validity();
  alignas(64) float dx[kLanes], dy[kLanes], dz[kLanes];
  if constexpr (kBW == DirectionTable::kBlock) {
    const size_t t0 = table.index(y0, x0);
    // Two lane loops: with the byte-wide validity in the same loop, GCC sized the vectors for
    // bytes and ran the double arithmetic two lanes an instruction, at every ISA level.
    APERTURE_LANE_LOOP
    for (int k = 0; k < kLanes; ++k) {
      const size_t t = t0 + size_t(k);
      worldDirectionLane(f, tx[t], ty[t], tz[t], dx[k], dy[k], dz[k]);
    }
    APERTURE_LANE_LOOP
    for (int k = 0; k < kLanes; ++k) valid[k] = tv[t0 + size_t(k)] ? -1 : 0;
    writeBlockLanesFromOrigin<kLanes>(out, f.eye, dx, dy, dz);
    return;
  }
  for (int row = 0; row < kBH; ++row) {
    const size_t t0 = table.index(y0 + row, x0);
    for (int col = 0; col < kBW; ++col) {
      const int k = row * kBW + col;
      const size_t t = t0 + size_t(col);
      worldDirectionLane(f, tx[t], ty[t], tz[t], dx[k], dy[k], dz[k]);
      valid[k] = tv[t] ? -1 : 0;
    }
  }
  writeBlockLanesFromOrigin<kLanes>(out, f.eye, dx, dy, dz);
}

/// The undistorted pinhole lens in closed form (no table): Lens::unproject of the source
/// pixel p, normalize((p − c) / f, 1) as GLM computes it (v · (1 / √(v·v))), then rotated.
struct PinholeLens {
  double fx, fy, cx, cy;
  double sourceOffset;  ///< source pixel minus raster position: 0 or −½ (sourcePixelOfRaster)
};

/// A kBW x kBH block of pixel centres of an undistorted pinhole lens, lanes past the image's
/// edges included. x and y are divided once per column and row of the block.
template <int kBW, int kBH>
void pinholeCentres(const CalibratedFrame& f, const PinholeLens& lens, int x0, int y0,
                    RayLanes& out, int* valid) {
  constexpr int kLanes = kBW * kBH;
  double xs[kBW], ys[kBH];
  for (int col = 0; col < kBW; ++col)
    xs[col] = ((((double(x0) + double(col)) + 0.5) + lens.sourceOffset) - lens.cx) / lens.fx;
  for (int row = 0; row < kBH; ++row)
    ys[row] = ((((double(y0) + double(row)) + 0.5) + lens.sourceOffset) - lens.cy) / lens.fy;
  alignas(64) float dx[kLanes], dy[kLanes], dz[kLanes];
  alignas(64) double xl[kLanes], yl[kLanes];
  spreadOverLanes<kBW, kBH>(xs, ys, xl, yl);
  APERTURE_LANE_LOOP
  for (int k = 0; k < kLanes; ++k) {
    const double x = xl[k], y = yl[k];
    const double s = 1.0 / std::sqrt((x * x + y * y) + 1.0);
    worldDirectionLane(f, x * s, y * s, s, dx[k], dy[k], dz[k]);
  }
  writeBlockLanesFromOrigin<kLanes>(out, f.eye, dx, dy, dz);
  writeBlockInImage<kBW, kBH>(x0, y0, f.width, f.height, valid);
}

class CalibratedCamera final : public CameraBase {
 public:
  CalibratedCamera(const CameraParams& p, const glm::dvec3& renderOrigin)
      : CameraBase(p, poseFrame(p), renderOrigin, "calibrated"), sensor_(calibratedSensorOf(p)) {
    rejectShift();
    // The pinhole part of the lens as the lecture's image plane at d = 1: u = (x − px) / fx,
    // v = (py − y) / fy for raster (x, y) and the principal point (px, py) in raster terms.
    const Lens& lens = sensor_.lens;
    const glm::dvec2 pp = rasterOfSourcePixel({lens.cx(), lens.cy()}, sensor_.pixelCentre);
    d_ = 1.0;
    vw_ = width_ / lens.fx();
    vh_ = height_ / lens.fy();
    shift_ = ImageWindow::shiftForPrincipalPoint(pp.x, pp.y, width_, height_);
    if (!readsDirectionTable(lens))
      pinhole_ = PinholeLens{lens.fx(), lens.fy(), lens.cx(), lens.cy(),
                             sensor_.pixelCentre == PixelCentre::Integer ? -0.5 : 0.0};
  }

  /// Every ray starts at the eye, at tnear 0.
  std::optional<glm::vec3> sharedRayOrigin() const override { return renderEye_; }

  /// A distorted lens at 1 spp: every ray is a pixel centre's, whose direction the table holds.
  std::optional<LensBlockBounds> lensBlockBounds() const override {
    static_assert(DirectionTable::kBlock == 4, "LensBlockBounds::blocks are 4 x 4 pixels");
    if (pinhole_ || spp_ != 1) return std::nullopt;
    const DirectionTable& table = this->table();
    LensBlockBounds b;
    // The table's camera space from render space: the inverse of worldDirection's rotation.
    b.cameraFromRender = openCvCameraFromFrame(frame_.u, frame_.v, frame_.w, renderEyeD_);
    b.eye = renderEyeD_;
    b.width = width_;
    b.height = height_;
    b.blocks = table.planeBounds().data();
    b.blockRays = table.blockRays().data();
    b.extent = table.planeExtent();
    b.minCosine = table.minCosine();
    return b;
  }

  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override {
    const bool centres = req.centreRay() || spp_ == 1;
    if (centres && generateCentres(req, out, valid)) return;
    // The lanes the table does not hold go to the lens Lens::kBatch at a time (unprojectBatch:
    // the same rays as rayAt's unproject, faster).
    constexpr int kMaxLanes = 16;
    APERTURE_CHECK_OP(req.lanes(), <=, kMaxLanes);
    glm::dvec2 samples[kMaxLanes];  // source pixel positions of the lanes left to the lens
    int laneOf[kMaxLanes], left = 0;
    const DirectionTable* table = centres && !pinhole_ ? &this->table() : nullptr;
    for (int k = 0; k < req.lanes(); ++k) {
      const LanePixel px = req.pixel(k);
      if (table && px.inImage(width_, height_)) {
        // The table holds exactly what rayAt computes here; (0, 0, 1) where there is no ray.
        valid[k] = table->valid(px.row, px.column) ? -1 : 0;
        setLane(out, k, renderEyeD_, worldDirection(table->at(px.row, px.column)));
        continue;
      }
      double x, y;
      samplePosition(px.row, px.column, req.sample, x, y);
      samples[left] = sourcePixelOfRaster(glm::dvec2(x, y), sensor_.pixelCentre);
      laneOf[left++] = k;
    }
    for (int first = 0; first < left; first += Lens::kBatch) {
      const int n = std::min(Lens::kBatch, left - first);
      glm::dvec3 dirs[Lens::kBatch];
      bool hasRay[Lens::kBatch];
      sensor_.lens.unprojectBatch(n, samples + first, dirs, hasRay);
      for (int c = 0; c < n; ++c) {
        const int k = laneOf[first + c];
        valid[k] = (hasRay[c] && req.inImage(k, width_, height_)) ? -1 : 0;
        setLane(out, k, renderEyeD_, worldDirection(hasRay[c] ? dirs[c] : glm::dvec3(0, 0, 1)));
      }
    }
  }

  bool ray(double x, double y, double, double, glm::dvec3& renderOrg,
           glm::dvec3& dir) const override {
    renderOrg = renderEyeD_;
    return rayAt(x, y, dir);
  }

  std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const override {
    const glm::dvec3 p = worldPoint - frame_.e;
    const glm::dvec3 cv(glm::dot(p, frame_.u), -glm::dot(p, frame_.v), -glm::dot(p, frame_.w));
    const std::optional<glm::dvec2> s = sensor_.lens.project(cv);
    if (!s) return std::nullopt;
    return rasterOfSourcePixel(*s, sensor_.pixelCentre);
  }

  ViewVolume viewVolume(double nearDist, double farDist) const override {
    // Distortion bends the frustum's planes; the whole space around e is a safe bound.
    return ViewVolume::allSpace(frame_.e, frame_.u, frame_.v, frame_.w, nearDist, farDist);
  }

 protected:
  std::optional<glm::dmat4> planeFromCamera() const override {
    if (sensor_.lens.distorted()) return std::nullopt;  // not projective: no worldToNDC
    glm::dmat4 m(0.0);  // as the perspective camera at d = 1 (GLM m[column][row])
    m[0][0] = 1.0;
    m[1][1] = 1.0;
    m[3][2] = 1.0;
    m[2][3] = 1.0;
    return m;
  }

  void describeExtra(CameraDescription& c) const override {
    const Lens& lens = sensor_.lens;
    if (!lens.distorted()) {
      c.screenWindowCenter = glm::dvec2(0.5 * (uLo() + uHi()), 0.5 * (vLo() + vHi()));
      c.screenWindowWidth = vw_;
    }
    LensProjection lp;
    lp.model = lens.info().name;
    lp.paramNames.assign(lens.info().paramNames.begin(), lens.info().paramNames.end());
    lp.params = lens.params();
    lp.pixelCentre = pixelCentreName(sensor_.pixelCentre);
    c.lens = lp;
    c.extra.emplace_back("valid_region", lens.validRegion().text(lens.overTheta()));
  }

  void describeCounts(CameraDescription& c) const override {
    c.extra.emplace_back(kValidPixelsExtra,
                         cat(validPixels(), " of ", size_t(width_) * size_t(height_)));
  }

 private:
  /// The world direction of camera-space direction d (OpenCV axes): d.x·U − d.y·V − d.z·W,
  /// normalised with one reciprocal (worldDirectionLane computes the same, term by term).
  glm::dvec3 worldDirection(const glm::dvec3& d) const {
    const glm::dvec3 g = (d.x * frame_.u - d.y * frame_.v) - d.z * frame_.w;
    const double inv = 1.0 / std::sqrt((g.x * g.x + g.y * g.y) + g.z * g.z);
    return g * inv;
  }

  /// Pixel centres in the frame loop's block shapes: the closed-form kernel of an undistorted
  /// pinhole, else the table kernel for blocks inside the image on the table's grid. False
  /// for the requests neither takes (the generic loop then fills them).
  bool generateCentres(const PacketRequest& req, RayLanes& out, int* valid) const {
    const CalibratedFrame f{frame_.u, frame_.v, frame_.w, renderEyeD_, width_, height_};
    if (pinhole_)
      return withBlockShape(req.blockW, req.blockH, [&](auto bw, auto bh) {
        constexpr int kBW = decltype(bw)::value, kBH = decltype(bh)::value;
        runKernel<&pinholeCentres<kBW, kBH>>(f, *pinhole_, req.x0, req.y0, out, valid);
      });
    constexpr int kB = DirectionTable::kBlock;
    const bool whole = req.x0 + req.blockW <= width_ && req.y0 + req.blockH <= height_;
    if (!whole || req.x0 % kB + req.blockW > kB) return false;
    return withBlockShape(req.blockW, req.blockH, [&](auto bw, auto bh) {
      constexpr int kBW = decltype(bw)::value, kBH = decltype(bh)::value;
      runKernel<&tableCentres<kBW, kBH>>(f, table(), req.x0, req.y0, out, valid);
    });
  }

  /// Pixels with a ray: every pixel of an undistorted pinhole (its inverse refuses none).
  size_t validPixels() const {
    return pinhole_ ? size_t(width_) * size_t(height_) : table().validCount();
  }

  bool rayAt(double x, double y, glm::dvec3& dir) const {
    const std::optional<glm::dvec3> d = sensorDirection(sensor_, x, y);
    dir = worldDirection(d.value_or(glm::dvec3(0.0, 0.0, 1.0)));  // the axis where there is none
    return d.has_value();
  }

  /// The distorted lens's direction table, taken from the cache or built at the first call
  /// (from any thread; the others wait for it). A camera made only to be checked, as a job's
  /// cameras are when it is read, or located (worldView, the automatic preview range) builds
  /// none; its first ray and its description (the valid-pixel count) do. The frame loop's
  /// ImagePlan describes the camera on the caller's thread, so the table (built by a parallel
  /// loop) is never first asked for by a worker inside the frame loop.
  const DirectionTable& table() const {
    std::call_once(tableOnce_, [this] { table_ = DirectionTable::of(sensor_); });
    return *table_;
  }

  CalibratedSensor sensor_;
  /// The undistorted pinhole in closed form, or else the distorted lens, whose rays are its
  /// table's (table()).
  std::optional<PinholeLens> pinhole_;
  mutable std::once_flag tableOnce_;
  mutable std::shared_ptr<const DirectionTable> table_;
};

std::unique_ptr<CameraBase> makeCalibratedCamera(const CameraParams& p,
                                                 const glm::dvec3& renderOrigin) {
  return std::make_unique<CalibratedCamera>(p, renderOrigin);
}

using K = ParamKind;

std::vector<const char*> lensModelNames() {
  std::vector<const char*> v;
  for (const LensModelInfo& m : lensModels()) v.push_back(m.name);
  return v;
}

const ParamSpec kIntrinsics =
    ParamSpec("intrinsics", K::Numbers, fieldAccess<&CameraParams::intrinsics>())
        .withUnit("pixels")
        .withHelp(
            "Focal lengths and principal point fx,fy,cx,cy (pixel convention: pixel_centre); "
            "selects the calibrated camera")
        .withDefaultRule("none (required)")
        .withCount(4)
        .withSelectsModel("calibrated");
const ParamSpec kLensModel =
    ParamSpec("lens_model", K::Choice, fieldAccess<&CameraParams::lensModel>())
        .withHelp("COLMAP camera model of the lens (src/colmap/sensor/models.h)")
        .withChoicesNow(lensModelNames);
const ParamSpec kDistortion =
    ParamSpec("distortion", K::Numbers, fieldAccess<&CameraParams::distortion>())
        .withHelp(
            "The lens model's distortion coefficients in COLMAP's order (OPENCV: k1,k2,p1,p2; "
            "OPENCV_FISHEYE: k1,k2,k3,k4; ...)")
        .withDefaultRule("all zero")
        .withNeeds({"lens_model"});
const ParamSpec kPixelCentre =
    ParamSpec("pixel_centre", K::Choice, fieldAccess<&CameraParams::pixelCentre>())
        .withHelp(
            "Where the intrinsics put pixel (i, j)'s centre: half-integer = (j + 0.5, i + 0.5) "
            "as COLMAP and nerfstudio, integer = (j, i) as OpenCV")
        .withChoices({"half-integer", "integer"});
const ParamSpec kWorldToCamera =
    ParamSpec("world_to_camera", K::Numbers, fieldAccess<&CameraParams::worldToCamera>())
        .withHelp("4x4 world-to-camera matrix, row-major, in `convention` axes")
        .withDefaultRule("none (eye, at / dir and up pose the camera)")
        .withConflicts({"camera_to_world", "eye", "at", "dir", "up"})
        .withCount(16)
        .withSelectsModel("calibrated");
const ParamSpec kCameraToWorld =
    ParamSpec("camera_to_world", K::Numbers, fieldAccess<&CameraParams::cameraToWorld>())
        .withHelp(
            "4x4 camera-to-world matrix, row-major, in `convention` axes (nerfstudio's "
            "transform_matrix, Blender's matrix_world)")
        .withDefaultRule("none (eye, at / dir and up pose the camera)")
        .withConflicts({"world_to_camera", "eye", "at", "dir", "up"})
        .withCount(16)
        .withSelectsModel("calibrated");
const ParamSpec kConvention =
    ParamSpec("convention", K::Choice, fieldAccess<&CameraParams::convention>())
        .withHelp(
            "Camera axes of the pose matrix: opencv = x right, y down, z forward (COLMAP); "
            "opengl, blender = x right, y up, z backwards")
        .withChoices({"opencv", "opengl", "blender"});

}  // namespace

const CameraModel& calibratedModel() {
  static const CameraModel m{
      "calibrated",
      "a calibrated lens (COLMAP's models, exact inverse distortion) posed by a matrix",
      makeCalibratedCamera,
      joinParamSpecs({commonParamSpecs(),
                      {&kIntrinsics, &kLensModel, &kDistortion, &kPixelCentre, &kWorldToCamera,
                       &kCameraToWorld, &kConvention}})};
  return m;
}

}  // namespace aperture
