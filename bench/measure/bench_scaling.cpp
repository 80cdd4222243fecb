#include "bench/measure/bench_scaling.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "apps/services/scene_setup.h"
#include "core/io/atomic_file.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"

extern char** environ;

namespace aperture::app {

namespace {

/// The spheres generator's range of tris= (core/mesh/procedural.cpp).
constexpr double kMinScalingTriangles = 100;
constexpr double kMaxScalingTriangles = 4e8;

/// A "Key:   123 kB" line of /proc/self/status in bytes; 0 when absent.
uint64_t procStatusBytes(const char* key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(key) + ":";
  while (std::getline(in, line))
    if (line.rfind(prefix, 0) == 0)
      return std::strtoull(line.c_str() + prefix.size(), nullptr, 10) * 1024;
  return 0;
}

/// Each argument of this process after argv[0], from /proc/self/cmdline (NUL-separated).
std::vector<std::string> ownArguments() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::vector<std::string> args;
  std::string arg;
  while (std::getline(in, arg, '\0')) args.push_back(arg);
  if (!args.empty()) args.erase(args.begin());
  return args;
}

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      return colon == std::string::npos ? line
                                        : line.substr(line.find_first_not_of(' ', colon + 1));
    }
  return "unknown";
}

std::string shellQuoted(const std::vector<std::string>& words) {
  std::string out;
  for (const std::string& w : words) {
    if (!out.empty()) out += ' ';
    const bool plain =
        w.find_first_not_of(
            "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_.,/=:") ==
        std::string::npos;
    if (plain && !w.empty()) {
      out += w;
      continue;
    }
    out += '\'';
    for (char c : w) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    out += '\'';
  }
  return out;
}

/// Runs `exe` with `args`, its stdout sent to our stderr (our stdout holds only the table);
/// returns its wait status.
int runChild(const std::string& exe, const std::vector<std::string>& args) {
  std::vector<char*> argv;
  std::string name = exe;
  argv.push_back(name.data());
  std::vector<std::string> copy = args;
  for (std::string& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, STDERR_FILENO, STDOUT_FILENO);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (err != 0) throw Error(cat("bench --scaling: cannot start ", exe, ": ", std::strerror(err)));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw Error(cat("bench --scaling: waitpid: ", std::strerror(errno)));
  return status;
}

std::string describeStatus(int status) {
  if (WIFEXITED(status)) return cat("exited with status ", WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return cat("was killed by signal ", WTERMSIG(status));
  return "ended abnormally";
}

double perTriangle(double bytes, double triangles) { return triangles > 0 ? bytes / triangles : 0; }

/// One table row from a child's bench JSON.
nlohmann::json scalingRow(uint64_t requested, bool compact, const nlohmann::json& b) {
  const nlohmann::json& mem = b.at("memory");
  const double tris = b.at("config").at("triangles").get<double>();
  const double peak = mem.at("peak_rss_bytes").get<double>();
  const nlohmann::json& c = b.at("config");
  const std::string bvh =
      cat(c.at("bvh_quality").get<std::string>(),
          c.at("robust").get<bool>() ? " robust" : " not robust", compact ? " compact" : "");
  return {{"requested_triangles", requested},
          {"triangles", tris},
          {"compact", compact},
          {"bvh", bvh},
          {"load_seconds", b.at("load_seconds")},
          {"build_seconds", b.at("build_seconds_median")},
          {"peak_rss_bytes", peak},
          {"peak_rss_bytes_per_triangle", perTriangle(peak, tris)},
          {"peak_rss_after_build_bytes", mem.at("peak_rss_after_build_bytes")},
          {"peak_rss_with_baseline_bytes", mem.at("peak_rss_with_baseline_bytes")},
          {"mesh_bytes", mem.at("mesh_bytes")},
          {"mesh_bytes_per_triangle", perTriangle(mem.at("mesh_bytes").get<double>(), tris)},
          {"embree_bytes", b.at("embree_bytes")},
          {"embree_bytes_per_triangle", b.at("embree_bytes_per_triangle")},
          {"mrays_per_s", b.at("mrays_per_s_median")},
          {"baseline_mrays_per_s", b.at("baseline_mrays_per_s_median")},
          {"render_over_baseline", b.at("render_over_baseline")},
          {"estimate_bytes", mem.at("estimate_bytes")},
          {"estimate_error_percent", mem.at("estimate_error_percent")}};
}

std::string sizeText(double triangles) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", triangles);
  return buf;
}

std::string markdownTable(const nlohmann::json& rows) {
  std::ostringstream md;
  md << "| triangles | BVH | load s | build s | peak RSS MB | peak B/tri | mesh B/tri | Embree "
        "B/tri | Mrays/s | baseline Mrays/s | ratio | estimate MB | estimate error |\n"
     << "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  char buf[512];
  for (const nlohmann::json& r : rows) {
    std::snprintf(
        buf, sizeof buf,
        "| %s | %s | %.2f | %.2f | %.0f | %.1f | %.1f | %.1f | %.1f | %.1f | %.3f | %.0f "
        "| %+.1f %% |\n",
        sizeText(r.at("triangles").get<double>()).c_str(), r.at("bvh").get<std::string>().c_str(),
        r.at("load_seconds").get<double>(), r.at("build_seconds").get<double>(),
        r.at("peak_rss_bytes").get<double>() / 1e6,
        r.at("peak_rss_bytes_per_triangle").get<double>(),
        r.at("mesh_bytes_per_triangle").get<double>(),
        r.at("embree_bytes_per_triangle").get<double>(), r.at("mrays_per_s").get<double>(),
        r.at("baseline_mrays_per_s").get<double>(), r.at("render_over_baseline").get<double>(),
        r.at("estimate_bytes").get<double>() / 1e6, r.at("estimate_error_percent").get<double>());
    md << buf;
  }
  return md.str();
}

/// A fresh directory under /tmp for the children's figures, removed with what it holds.
struct ScratchDirectory {
  std::string path;
  ScratchDirectory() {
    char name[] = "/tmp/aperture-scaling-XXXXXX";
    if (!::mkdtemp(name))
      throw Error(cat("bench --scaling: cannot make a directory in /tmp: ", std::strerror(errno)));
    path = name;
  }
  ~ScratchDirectory() {
    std::remove((path + "/row.json").c_str());
    ::rmdir(path.c_str());
  }
  ScratchDirectory(const ScratchDirectory&) = delete;
  ScratchDirectory& operator=(const ScratchDirectory&) = delete;
};

/// "out.json" -> "out.md"; any other name gets ".md" appended.
std::string readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(cat("bench --scaling: cannot read the child's figures from ", path));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string markdownPathOf(const std::string& json) {
  const std::string ext = ".json";
  if (json.size() > ext.size() && json.compare(json.size() - ext.size(), ext.size(), ext) == 0)
    return json.substr(0, json.size() - ext.size()) + ".md";
  return json + ".md";
}

}  // namespace

std::vector<uint64_t> parseScalingSizes(const std::string& text) {
  std::vector<uint64_t> sizes;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double v = item.empty() ? NAN : std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v) || v != std::floor(v) ||
        v < kMinScalingTriangles || v > kMaxScalingTriangles)
      throw Error(cat("--scaling-sizes: '", item, "' in '", text,
                      "' is not a triangle count (a whole number in [100, 4e8], e.g. 1e5 or "
                      "2500000)"));
    sizes.push_back(uint64_t(v));
  }
  if (sizes.empty() || text.back() == ',')
    throw Error(cat("--scaling-sizes: '", text, "' lists no sizes (e.g. 1e5,1e6,1e7)"));
  return sizes;
}

std::string scalingMeshSpec(uint64_t triangles) {
  return cat("procedural:spheres?tris=", triangles);
}

std::vector<std::string> scalingChildArguments(const std::vector<std::string>& parent,
                                               uint64_t triangles, bool compact,
                                               const std::string& rowJson) {
  const std::vector<std::string> dropped = {"--scaling", "--compact", "--baseline", "--quiet"};
  const std::vector<std::string> droppedWithValue = {"--scaling-sizes", "--json", "--mesh",
                                                     "--builds"};
  auto listed = [](const std::vector<std::string>& names, const std::string& a) {
    return std::find(names.begin(), names.end(), a) != names.end();
  };
  auto assigns = [](const std::vector<std::string>& names, const std::string& a) {
    return std::any_of(names.begin(), names.end(),
                       [&](const std::string& n) { return a.rfind(n + "=", 0) == 0; });
  };
  std::vector<std::string> args;
  for (size_t k = 0; k < parent.size(); ++k) {
    const std::string& a = parent[k];
    if (listed(droppedWithValue, a))
      ++k;  // and its value
    else if (!listed(dropped, a) && !assigns(droppedWithValue, a))
      args.push_back(a);
  }
  args.push_back("--mesh");
  args.push_back(scalingMeshSpec(triangles));
  for (const char* a : {"--baseline", "--builds", "1", "--quiet", "--json"}) args.push_back(a);
  args.push_back(rowJson);
  if (compact) args.push_back("--compact");
  return args;
}

uint64_t peakResidentBytes() { return procStatusBytes("VmHWM"); }

nlohmann::json benchMemoryReport(const LoadedScene& loaded, const MemoryEstimate& estimate,
                                 const MemoryPeaks& peaks) {
  uint64_t meshBytes = 0;
  for (const Mesh& m : loaded.meshes) meshBytes += meshBufferBytes(m);
  const double peak = double(peaks.beforeBaseline);
  return {{"peak_rss_after_build_bytes", peaks.afterBuild},
          {"peak_rss_bytes", peaks.beforeBaseline},
          {"peak_rss_with_baseline_bytes", peaks.atEnd},
          {"mesh_bytes", meshBytes},
          {"estimate_bytes", estimate.total()},
          {"estimate_mesh_bytes", estimate.meshBytes},
          {"estimate_bvh_bytes", estimate.bvhBytes},
          {"estimate_framebuffer_bytes", estimate.framebufferBytes},
          {"estimate_runtime_bytes", estimate.runtimeBytes},
          {"estimate_error_percent",
           peak > 0 ? 100.0 * (double(estimate.total()) - peak) / peak : 0.0}};
}

MemoryEstimate benchMemoryEstimate(const SceneOptions& o, int width, int height,
                                   const AovSet& aovs) {
  std::vector<std::string> specs;
  for (const MeshPlacement& m : o.spec().meshes) specs.push_back(m.spec);
  return estimateMemory(specs, uint64_t(width), uint64_t(height), aovs, 0, o.buildOptions());
}

int runScaling(const ScalingRun& run) {
  char exe[4096];
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) throw Error("bench --scaling: cannot find this executable (/proc/self/exe)");
  exe[n] = '\0';
  const std::vector<std::string> parent = ownArguments();
  const ScratchDirectory scratch;
  const std::string rowJson = scratch.path + "/row.json";

  nlohmann::json rows = nlohmann::json::array(), config, commands = nlohmann::json::array();
  std::vector<bool> modes = {false};
  if (run.compact) modes.push_back(true);
  for (bool compact : modes)
    for (uint64_t tris : run.sizes) {
      const std::vector<std::string> args = scalingChildArguments(parent, tris, compact, rowJson);
      const std::string command = shellQuoted({exe}) + " " + shellQuoted(args);
      std::fprintf(stderr, "bench --scaling: %s triangles%s: %s\n", sizeText(double(tris)).c_str(),
                   compact ? " (compact BVH)" : "", command.c_str());
      std::remove(rowJson.c_str());
      const int status = runChild(exe, args);
      if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw Error(cat("bench --scaling: the bench of ", tris, " triangles",
                        compact ? " (compact BVH)" : "", " ", describeStatus(status),
                        " (its messages are above); command: ", command));
      const nlohmann::json child = nlohmann::json::parse(readWholeFile(rowJson));
      if (config.is_null()) config = child.at("config");
      rows.push_back(scalingRow(tris, compact, child));
      commands.push_back(command);
    }

  config.erase("meshes");
  config.erase("triangles");
  config.erase("compact");
  config["cpu"] = cpuModel();
  const std::string table = markdownTable(rows);
  std::printf("%s", table.c_str());
  if (!run.json.empty()) {
    const nlohmann::json out = {{"config", config},
                                {"command", shellQuoted({exe}) + " " + shellQuoted(parent)},
                                {"child_commands", commands},
                                {"peak_rss_measured_as",
                                 "VmHWM of each size's own child process after its frames, before "
                                 "the baseline's stored rays"},
                                {"rows", rows}};
    writeTextAtomically(run.json, out.dump(2) + "\n");
    writeTextAtomically(markdownPathOf(run.json), table);
  }
  return 0;
}

}  // namespace aperture::app
