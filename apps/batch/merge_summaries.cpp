#include "apps/batch/merge_summaries.h"

#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/jobs/job.h"
#include "apps/services/view.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"

namespace aperture::app {

namespace {

using nlohmann::json;

struct SummaryFile {
  std::string path;
  json content;
};

json readJsonFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(cat("--merge-summaries: cannot read '", path, "'"));
  std::stringstream text;
  text << in.rdbuf();
  try {
    return json::parse(text.str());
  } catch (const json::exception& e) {
    throw Error(cat("--merge-summaries: '", path, "' is not JSON: ", e.what()));
  }
}

/// Reads a summary and checks the keys the merge uses.
SummaryFile readSummary(const std::string& path) {
  SummaryFile s{path, readJsonFile(path)};
  const json& j = s.content;
  auto bad = [&](const std::string& what) {
    return Error(cat("--merge-summaries: '", path, "' is not a summary of aperture batch: ", what));
  };
  if (!j.is_object() || !j.contains("job") || !j["job"].is_string()) throw bad("no \"job\" path");
  if (!j.contains("images_in_job") || !j["images_in_job"].is_number_unsigned())
    throw bad("no \"images_in_job\" count");
  if (!j.contains("images") || !j["images"].is_array()) throw bad("no \"images\" list");
  const size_t count = j["images_in_job"];
  for (const json& e : j["images"]) {
    if (!e.is_object() || !e.contains("index") || !e["index"].is_number_unsigned() ||
        e["index"].get<size_t>() >= count || !e.contains("status") || !e["status"].is_string())
      throw bad(
          cat("image entry ", e.dump(), " needs an \"index\" below ", count, " and a \"status\""));
  }
  return s;
}

void checkSameJob(const std::vector<SummaryFile>& files) {
  const SummaryFile& first = files.front();
  for (const SummaryFile& f : files) {
    if (f.content["job"] != first.content["job"])
      throw Error(cat("--merge-summaries: '", first.path, "' and '", f.path,
                      "' are summaries of different jobs (", first.content["job"].dump(), " and ",
                      f.content["job"].dump(), ")"));
    if (f.content["images_in_job"] != first.content["images_in_job"])
      throw Error(cat("--merge-summaries: '", first.path, "' and '", f.path,
                      "' are summaries of different versions of job ", first.content["job"].dump(),
                      " (", first.content["images_in_job"].dump(), " and ",
                      f.content["images_in_job"].dump(), " images)"));
  }
}

/// Higher is better: done (ok, skipped), failed, interrupted, anything else.
int statusRank(const std::string& status) {
  if (status == "ok" || status == "skipped") return 3;
  if (status == "failed") return 2;
  if (status == "interrupted") return 1;
  return 0;
}

bool isDone(const json& entry) { return statusRank(entry["status"]) == 3; }

/// The best entry for each image index that some summary lists, tagged with its file.
std::map<size_t, json> bestEntries(const std::vector<SummaryFile>& files) {
  std::map<size_t, json> best;
  for (const SummaryFile& f : files)
    for (json e : f.content["images"]) {
      e["summary"] = f.path;
      const size_t index = e["index"];
      auto it = best.find(index);
      if (it == best.end())
        best.emplace(index, e);
      else if (statusRank(e["status"]) > statusRank(it->second["status"]))
        it->second = e;
    }
  return best;
}

/// The job's images, to name those no summary lists; empty (after a note) when the job file
/// cannot be read or no longer has `count` images.
std::vector<JobImage> jobImages(const std::string& jobPath, size_t count, bool quiet) {
  try {
    std::vector<JobImage> images;
    for (Job& scene : readJobFile(jobPath).scenes)
      images.insert(images.end(), scene.images.begin(), scene.images.end());
    if (images.size() == count) return images;
    if (!quiet)
      std::fprintf(stderr,
                   "aperture: merge: %s now has %zu images, the summaries %zu; naming images "
                   "by index\n",
                   jobPath.c_str(), images.size(), count);
  } catch (const Error& e) {
    if (!quiet) std::fprintf(stderr, "aperture: merge: naming images by index: %s\n", e.what());
  }
  return {};
}

/// "camera frame N" for an entry that has camera and frame, else "image I".
std::string entryLabel(const json& e) {
  if (e.contains("camera") && e["camera"].is_string() && e.contains("frame") &&
      e["frame"].is_number_integer())
    return cat(e["camera"].get<std::string>(), " frame ", e["frame"].get<int>());
  return cat("image ", e["index"].get<size_t>());
}

/// An entry for an image that no summary lists.
json unreportedEntry(size_t index, const std::vector<JobImage>& images) {
  json e = {{"index", index}, {"status", "missing"}};
  if (index < images.size()) {
    e["camera"] = images[index].camera;
    e["frame"] = images[index].frame;
    e["output"] = images[index].output;
  }
  return e;
}

/// The merged summary: totals, "missing" and one entry per image of the job, in index order.
json mergedSummary(const std::vector<SummaryFile>& files, const std::vector<std::string>& inputs,
                   bool quiet) {
  const std::string jobPath = files.front().content["job"];
  const size_t count = files.front().content["images_in_job"];
  const std::map<size_t, json> best = bestEntries(files);
  const std::vector<JobImage> images =
      best.size() < count ? jobImages(jobPath, count, quiet) : std::vector<JobImage>();
  json entries = json::array(), missing = json::array();
  std::map<std::string, size_t> byStatus;
  double renderSeconds = 0, writeSeconds = 0, rays = 0;
  for (size_t index = 0; index < count; ++index) {
    auto it = best.find(index);
    const json e = it != best.end() ? it->second : unreportedEntry(index, images);
    ++byStatus[e["status"].get<std::string>()];
    if (!isDone(e)) missing.push_back(entryLabel(e));
    renderSeconds += e.value("render_seconds", 0.0);
    writeSeconds += e.value("write_seconds", 0.0);
    rays += e.value("rays", 0.0);
    entries.push_back(e);
  }
  return {{"job", jobPath},
          {"aperture_version", APERTURE_VERSION},
          {"merged", inputs},
          {"images_in_job", count},
          {"images_ok", byStatus["ok"]},
          {"images_skipped", byStatus["skipped"]},
          {"images_failed", byStatus["failed"]},
          {"images_interrupted", byStatus["interrupted"]},
          {"images_unreported", count - best.size()},
          {"images_missing", missing.size()},
          {"missing", missing},
          {"render_seconds", renderSeconds},
          {"write_seconds", writeSeconds},
          {"rays", rays},
          {"images", entries}};
}

void reportMissing(const json& merged) {
  const std::string list =
      join(merged["missing"], ", ", [](const json& name) { return name.get<std::string>(); });
  std::fprintf(stderr, "aperture: merge: %zu of %zu images missing (no summary has them ok): %s\n",
               merged["images_missing"].get<size_t>(), merged["images_in_job"].get<size_t>(),
               list.c_str());
}

}  // namespace

int mergeSummaries(const std::string& outPath, const std::vector<std::string>& inputs, bool quiet) {
  if (inputs.empty()) throw Error("--merge-summaries: give the summaries to merge after OUT.json");
  std::vector<SummaryFile> files;
  for (const std::string& path : inputs) files.push_back(readSummary(path));
  checkSameJob(files);
  const json merged = mergedSummary(files, inputs, quiet);
  ensureParentDirectory(outPath, "--merge-summaries");
  writeTextAtomically(outPath, merged.dump(2) + "\n");
  const bool complete = merged["images_missing"].get<size_t>() == 0;
  if (!complete) reportMissing(merged);
  if (!quiet)
    std::fprintf(stderr, "aperture: merge: wrote %s (%zu summaries, %s)\n", outPath.c_str(),
                 inputs.size(), complete ? "every image done" : "images missing");
  return complete ? 0 : 1;
}

}  // namespace aperture::app
