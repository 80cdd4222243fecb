#include "bench/measure/tradeoff.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include "cameras/registry/registry.h"
#include "core/io/image.h"
#include "core/util/error.h"
#include "core/util/stats.h"

namespace aperture::app {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// What the study renders: color for the image error, depth and primID for the geometry.
constexpr AovMask kStudyAovs = kAovColor | kAovDepth | kAovPrimId;

bool sameBuild(const BuildOptions& a, const BuildOptions& b) {
  return a.quality == b.quality && a.robust == b.robust && a.compact == b.compact;
}

bool sameSetting(const TradeoffSetting& a, const TradeoffSetting& b) {
  return sameBuild(a.build, b.build) && a.placement == b.placement &&
         a.render.packetWidth == b.render.packetWidth && a.render.tileSize == b.render.tileSize &&
         a.render.spp == b.render.spp && a.exr.compression == b.exr.compression &&
         a.exr.halfColor == b.exr.halfColor;
}

std::string buildName(const BuildOptions& b) {
  return cat(bvhQualityName(b.quality), b.robust ? " robust" : "", b.compact ? " compact" : "");
}

const char* placementName(Placement p) {
  return p == Placement::WorldSpace ? "world-space" : "camera-relative";
}

/// Meshes in one placement with the Embree scenes built over them, by build options.
class Study {
 public:
  explicit Study(const TradeoffConfig& c) : c_(c) {}

  std::vector<TradeoffRow> run() {
    const std::vector<TradeoffSetting> settings = tradeoffSettings(c_);
    fs::create_directories(c_.tempDir);
    // The reference first, so every row can be compared as soon as it is rendered.
    reference_ = renderReference(c_.referenceSpp);
    std::vector<TradeoffRow> rows;
    for (const TradeoffSetting& s : settings) {
      rows.push_back(measure(s, settings.front()));
      const TradeoffRow& r = rows.back();
      if (!c_.quiet)
        std::fprintf(stderr,
                     "aperture: tradeoff %-15s %-22s PSNR %7.2f dB, RMSE %.5f, primID %.4f%%, "
                     "frame %.4f s, %.1f Mrays/s, build %.3f s\n",
                     r.setting.knob.c_str(), r.setting.value.c_str(), r.psnr, r.rmse,
                     100 * r.primIdMismatch, r.frameSeconds, r.mraysPerSecond, r.buildSeconds);
    }
    markPareto(rows);
    return rows;
  }

 private:
  /// The meshes loaded once per placement, through the one scene set-up.
  const LoadedScene& meshes(Placement p) {
    auto& slot = loaded_[p];
    if (!slot) {
      SceneSpec spec = c_.scene.spec();
      spec.placement = p;
      slot = std::make_unique<LoadedScene>(loadSceneMeshes(spec, c_.quiet));
      orderScatteredMeshes(*slot, spec.build, c_.quiet);
    }
    return *slot;
  }

  /// A fresh scene (its build time and memory are this row's).
  std::unique_ptr<Scene> build(Placement p, const BuildOptions& b) {
    return std::make_unique<Scene>(device_, meshes(p).objects, b);
  }

  std::unique_ptr<Camera> camera(const Scene& scene, int spp) const {
    CameraParams p = c_.camera;
    p.spp = spp;
    return makeCamera(p, scene.renderOrigin());
  }

  Framebuffer render(const Scene& scene, const RenderSettings& rs, RenderStats* stats = nullptr) {
    const auto cam = camera(scene, rs.spp);
    Framebuffer fb(c_.camera.width, c_.camera.height, kStudyAovs);
    const RenderStats st = renderImage(scene, *cam, rs, fb);
    if (stats) *stats = st;
    return fb;
  }

  static BuildOptions referenceBuild() {
    BuildOptions b;
    b.quality = BvhQuality::High;
    b.robust = true;
    b.compact = false;
    return b;
  }

  /// The reference settings (robust, high, camera-relative) rendered at `spp`.
  Framebuffer renderReference(int spp) {
    if (!referenceScene_) referenceScene_ = build(Placement::CameraRelative, referenceBuild());
    RenderSettings rs = c_.base;
    rs.spp = spp;
    const auto start = Clock::now();
    Framebuffer fb = render(*referenceScene_, rs);
    if (!c_.quiet)
      std::fprintf(stderr, "aperture: tradeoff reference at %d spp: %.3f s\n", spp,
                   std::chrono::duration<double>(Clock::now() - start).count());
    return fb;
  }

  const Framebuffer& referenceAt(int spp) {
    if (spp == c_.referenceSpp) return reference_;
    auto it = sameSpp_.find(spp);
    if (it == sameSpp_.end()) it = sameSpp_.emplace(spp, renderReference(spp)).first;
    return it->second;
  }

  void compare(const Framebuffer& fb, int spp, TradeoffRow& r) {
    const ImageDiff toReference = compareFramebuffers(fb, reference_, 1.0);
    r.rmse = toReference.rmse;
    r.psnr = toReference.psnr;
    r.maxError = toReference.maxError;
    const ImageDiff same = compareFramebuffers(fb, referenceAt(spp), 1.0);
    r.rmseSameSpp = same.rmse;
    r.primIdMismatch = same.primIdMismatch;
    r.depthRelError = same.depthRelError;
  }

  /// Median write time and the size of `fb` written with `exr`; the file read back.
  Framebuffer writeAndRead(const Framebuffer& fb, const Scene& scene, int spp,
                           const ExrOptions& exr, TradeoffRow& r) {
    ExrMetadata meta;
    meta.camera = camera(scene, spp)->describe();
    const std::string path =
        (fs::path(c_.tempDir) / cat("tradeoff-", exrCompressionName(exr.compression),
                                    exr.halfColor ? "-half" : "-float", ".exr"))
            .string();
    const ExrEncodingThreads encoding(c_.encodeThreads, exr.compression);
    std::vector<double> times;
    for (int k = 0; k < std::max(1, c_.writes); ++k) {
      const auto start = Clock::now();
      writeExr(path, fb, meta, exr);
      times.push_back(std::chrono::duration<double>(Clock::now() - start).count());
    }
    r.writeSeconds = median(times);
    r.exrBytes = static_cast<long long>(fs::file_size(path));
    Framebuffer back = readExr(path);
    fs::remove(path);
    return back;
  }

  /// A row that only changes how the file is written: the base frame and its timing, written
  /// with the row's EXR options and compared after reading it back.
  TradeoffRow measureFileOnly(const TradeoffSetting& s, TradeoffRow& r) {
    r.frameSeconds = baseRow_.frameSeconds;
    r.mraysPerSecond = baseRow_.mraysPerSecond;
    r.buildSeconds = baseRow_.buildSeconds;
    r.embreeBytes = baseRow_.embreeBytes;
    const Framebuffer back = writeAndRead(*baseFrame_, *baseScene_, s.render.spp, s.exr, r);
    compare(back, s.render.spp, r);
    return r;
  }

  /// Renders the warm-up and timed frames of `scene` with `rs`; the medians go to `r`, the
  /// last frame is returned.
  Framebuffer timeFrames(const Scene& scene, const RenderSettings& rs, TradeoffRow& r) {
    const auto cam = camera(scene, rs.spp);
    Framebuffer fb(c_.camera.width, c_.camera.height, kStudyAovs);
    std::vector<double> seconds, mrays;
    for (int f = 0; f < c_.warmup + std::max(1, c_.frames); ++f) {
      const RenderStats st = renderImage(scene, *cam, rs, fb);
      if (f < c_.warmup) continue;
      seconds.push_back(st.seconds);
      mrays.push_back(st.mraysPerSecond());
    }
    r.frameSeconds = median(seconds);
    r.mraysPerSecond = median(mrays);
    return fb;
  }

  TradeoffRow measure(const TradeoffSetting& s, const TradeoffSetting& base) {
    TradeoffRow r;
    r.setting = s;
    // Rows that only change how the file is written reuse the base frame and its timing.
    const bool exrOnly =
        s.knob != "base" && sameBuild(s.build, base.build) && s.placement == base.placement &&
        s.render.packetWidth == base.render.packetWidth &&
        s.render.tileSize == base.render.tileSize && s.render.spp == base.render.spp;
    if (exrOnly && baseFrame_) return measureFileOnly(s, r);

    // The base scene is kept for the knobs that do not change the build.
    std::unique_ptr<Scene> own;
    const Scene* scene = nullptr;
    if (baseScene_ && sameBuild(s.build, base.build) && s.placement == base.placement) {
      scene = baseScene_.get();
    } else {
      own = build(s.placement, s.build);
      scene = own.get();
    }
    r.buildSeconds = scene->stats().buildSeconds;
    r.embreeBytes = scene->stats().embreeBytes;
    if (scene == baseScene_.get()) {
      r.buildSeconds = baseRow_.buildSeconds;
      r.embreeBytes = baseRow_.embreeBytes;
    }

    Framebuffer fb = timeFrames(*scene, s.render, r);
    compare(fb, s.render.spp, r);

    if (s.knob == "base") {
      writeAndRead(fb, *scene, s.render.spp, s.exr, r);
      baseRow_ = r;
      baseFrame_ = std::make_unique<Framebuffer>(std::move(fb));
      baseScene_ = own ? std::move(own) : nullptr;
    } else {
      // The file costs what the base's does: only the EXR knobs change it.
      r.writeSeconds = baseRow_.writeSeconds;
      r.exrBytes = baseRow_.exrBytes;
    }
    return r;
  }

  const TradeoffConfig& c_;
  Device device_;
  std::map<Placement, std::unique_ptr<LoadedScene>> loaded_;
  std::unique_ptr<Scene> referenceScene_, baseScene_;
  Framebuffer reference_;
  std::map<int, Framebuffer> sameSpp_;
  std::unique_ptr<Framebuffer> baseFrame_;
  TradeoffRow baseRow_;
};

std::string number(double v, int precision) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (std::isnan(v)) return "nan";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", precision, v);
  return buf;
}

std::string general(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

}  // namespace

std::vector<TradeoffSetting> tradeoffSettings(const TradeoffConfig& c) {
  TradeoffSetting base;
  base.knob = "base";
  base.build = c.scene.buildOptions();
  base.placement = c.scene.loadOptions().placement;
  base.render = c.base;
  base.exr = c.baseExr;
  base.value =
      cat(buildName(base.build), ", ", placementName(base.placement), ", packet ",
          base.render.packetWidth, ", tile ", base.render.tileSize, ", ", base.render.spp, " spp, ",
          base.exr.halfColor ? "half" : "float", " ", exrCompressionName(base.exr.compression));
  std::vector<TradeoffSetting> out{base};
  auto add = [&](const char* knob, const std::string& value,
                 const std::function<void(TradeoffSetting&)>& change) {
    TradeoffSetting s = base;
    s.knob = knob;
    s.value = value;
    change(s);
    const bool seen = std::any_of(out.begin(), out.end(),
                                  [&](const TradeoffSetting& o) { return sameSetting(o, s); });
    if (!seen) out.push_back(s);
  };

  for (BvhQuality q : {BvhQuality::Low, BvhQuality::Medium, BvhQuality::High})
    for (bool robust : {false, true})
      for (bool compact : {false, true}) {
        const BuildOptions b{q, robust, compact};
        add("bvh", buildName(b), [&](TradeoffSetting& s) { s.build = b; });
      }
  for (int w : {1, 4, 8, 16})
    add("packet", cat(w), [&](TradeoffSetting& s) { s.render.packetWidth = w; });
  const std::vector<int> spps = c.quick ? std::vector<int>{1, 4} : std::vector<int>{1, 4, 16, 64};
  for (int n : spps) add("spp", cat(n), [&](TradeoffSetting& s) { s.render.spp = n; });
  for (Placement p : {Placement::CameraRelative, Placement::WorldSpace})
    add("placement", placementName(p), [&](TradeoffSetting& s) { s.placement = p; });
  for (bool half : {false, true})
    add("exr_color", half ? "half" : "float", [&](TradeoffSetting& s) { s.exr.halfColor = half; });
  const std::vector<ExrCompression> compressions =
      c.quick ? std::vector<ExrCompression>{ExrCompression::None, ExrCompression::Zip,
                                            ExrCompression::Dwaa}
              : std::vector<ExrCompression>{
                    ExrCompression::None, ExrCompression::Rle,  ExrCompression::Zips,
                    ExrCompression::Zip,  ExrCompression::Piz,  ExrCompression::Pxr24,
                    ExrCompression::B44,  ExrCompression::Dwaa, ExrCompression::Dwab};
  for (ExrCompression comp : compressions)
    add("exr_compression", exrCompressionName(comp),
        [&](TradeoffSetting& s) { s.exr.compression = comp; });
  const std::vector<int> tiles =
      c.quick ? std::vector<int>{8, 32} : std::vector<int>{8, 16, 32, 64, 128};
  for (int t : tiles) add("tile", cat(t), [&](TradeoffSetting& s) { s.render.tileSize = t; });
  if (c.combinations && !c.quick)
    for (BvhQuality q : {BvhQuality::Low, BvhQuality::Medium})
      for (int n : {4, 16, 64})
        add("combo", cat(bvhQualityName(q), ", ", n, " spp"), [&](TradeoffSetting& s) {
          s.build.quality = q;
          s.render.spp = n;
        });
  return out;
}

std::vector<TradeoffRow> runTradeoff(const TradeoffConfig& config) {
  // The reference image's spp is a camera's spp: the spp spec's range.
  checkParamValue(*findCameraParamSpec("spp"), config.referenceSpp, "--reference-spp");
  if (config.frames < 1) throw Error(cat("--frames ", config.frames, " must be >= 1"));
  if (config.warmup < 0) throw Error(cat("--warmup ", config.warmup, " must be >= 0"));
  if (config.tempDir.empty()) throw Error("tradeoff: no temporary directory for the EXR knobs");
  validateRenderSettings(config.base);
  Study study(config);
  return study.run();
}

void markPareto(std::vector<TradeoffRow>& rows) {
  for (TradeoffRow& r : rows) {
    r.pareto = std::none_of(rows.begin(), rows.end(), [&](const TradeoffRow& o) {
      const bool noWorse = o.costSeconds() <= r.costSeconds() && o.rmse <= r.rmse;
      const bool better = o.costSeconds() < r.costSeconds() || o.rmse < r.rmse;
      return &o != &r && noWorse && better;
    });
  }
}

std::string tradeoffCsv(const std::vector<TradeoffRow>& rows) {
  std::ostringstream s;
  s << "knob,value,bvh_quality,robust,compact,placement,packet,tile,spp,exr_color,"
       "exr_compression,rmse,psnr_db,max_error,rmse_same_spp,primid_mismatch,depth_rel_error,"
       "frame_s,mrays_per_s,build_s,embree_bytes,exr_bytes,write_s,cost_s,pareto\n";
  for (const TradeoffRow& r : rows) {
    const TradeoffSetting& t = r.setting;
    s << t.knob << ",\"" << t.value << "\"," << bvhQualityName(t.build.quality) << ","
      << int(t.build.robust) << "," << int(t.build.compact) << "," << placementName(t.placement)
      << "," << t.render.packetWidth << "," << t.render.tileSize << "," << t.render.spp << ","
      << (t.exr.halfColor ? "half" : "float") << "," << exrCompressionName(t.exr.compression) << ","
      << general(r.rmse) << "," << number(r.psnr, 3) << "," << general(r.maxError) << ","
      << general(r.rmseSameSpp) << "," << general(r.primIdMismatch) << ","
      << general(r.depthRelError) << "," << general(r.frameSeconds) << ","
      << number(r.mraysPerSecond, 2) << "," << general(r.buildSeconds) << "," << r.embreeBytes
      << "," << r.exrBytes << "," << general(r.writeSeconds) << "," << general(r.costSeconds())
      << "," << int(r.pareto) << "\n";
  }
  return s.str();
}

namespace {

std::string label(const TradeoffRow& r) {
  return r.setting.knob == "base" ? std::string("base") : r.setting.knob + " " + r.setting.value;
}

/// The fastest row whose PSNR reaches `db`, or nullptr.
const TradeoffRow* fastestReaching(const std::vector<TradeoffRow>& rows, double db) {
  const TradeoffRow* best = nullptr;
  for (const TradeoffRow& r : rows)
    if (r.psnr >= db && (!best || r.costSeconds() < best->costSeconds())) best = &r;
  return best;
}

/// The lowest-error row costing at most `seconds`, or nullptr.
const TradeoffRow* bestWithin(const std::vector<TradeoffRow>& rows, double seconds) {
  const TradeoffRow* best = nullptr;
  for (const TradeoffRow& r : rows)
    if (r.costSeconds() <= seconds && (!best || r.rmse < best->rmse)) best = &r;
  return best;
}

}  // namespace

std::string tradeoffMarkdown(const std::vector<TradeoffRow>& rows, const std::string& title) {
  std::ostringstream s;
  s << "### " << title << "\n\n";
  s << "| knob | value | PSNR dB | RMSE | max err | RMSE same spp | primID diff % | Z rel err "
       "| frame ms | Mrays/s | build s | Embree MB | EXR KB | write ms | Pareto |\n"
       "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:-:|\n";
  for (const TradeoffRow& r : rows) {
    s << "| " << r.setting.knob << " | " << r.setting.value << " | " << number(r.psnr, 2) << " | "
      << general(r.rmse) << " | " << general(r.maxError) << " | " << general(r.rmseSameSpp) << " | "
      << number(100 * r.primIdMismatch, 3) << " | " << general(r.depthRelError) << " | "
      << number(1e3 * r.frameSeconds, 2) << " | " << number(r.mraysPerSecond, 1) << " | "
      << number(r.buildSeconds, 3) << " | " << number(r.embreeBytes / 1e6, 1) << " | "
      << number(r.exrBytes / 1e3, 0) << " | " << number(1e3 * r.writeSeconds, 1) << " | "
      << (r.pareto ? "★" : "") << " |\n";
  }
  s << "\nFrontier (cost = frame + write, ascending):";
  std::vector<const TradeoffRow*> front;
  for (const TradeoffRow& r : rows)
    if (r.pareto) front.push_back(&r);
  std::sort(front.begin(), front.end(), [](const TradeoffRow* a, const TradeoffRow* b) {
    return a->costSeconds() < b->costSeconds();
  });
  for (const TradeoffRow* r : front)
    s << "\n- " << label(*r) << ": " << number(1e3 * r->costSeconds(), 1) << " ms, PSNR "
      << number(r->psnr, 2) << " dB";
  s << "\n\nEqual error (fastest setting reaching a PSNR):\n";
  for (double db : {30.0, 40.0, 50.0}) {
    const TradeoffRow* r = fastestReaching(rows, db);
    s << "- " << number(db, 0) << " dB: "
      << (r ? cat(label(*r), " (", number(r->psnr, 2), " dB, ", number(1e3 * r->costSeconds(), 1),
                  " ms)")
            : std::string("no setting of the study reaches it"))
      << "\n";
  }
  const TradeoffRow* base = rows.empty() ? nullptr : &rows.front();
  if (base) {
    s << "\nEqual time (lowest error within a multiple of the base cost, "
      << number(1e3 * base->costSeconds(), 1) << " ms):\n";
    for (double k : {1.1, 4.0, 16.0}) {
      const TradeoffRow* r = bestWithin(rows, k * base->costSeconds());
      if (r)
        s << "- ≤ " << general(k) << "×: " << label(*r) << " (PSNR " << number(r->psnr, 2)
          << " dB, " << number(1e3 * r->costSeconds(), 1) << " ms)\n";
    }
  }
  return s.str();
}

}  // namespace aperture::app
