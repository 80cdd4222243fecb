#include "apps/jobs/job_json.h"

#include <algorithm>

#include "core/util/spelling.h"

namespace aperture::app {

Object::Object(const std::string& file, std::string path, const json& j,
               const std::vector<std::string>& known)
    : file_(file), path_(std::move(path)), j_(j) {
  if (!j.is_object()) fail(path_, cat("expected an object, got ", typeName(j)));
  for (const auto& item : j.items()) {
    if (std::find(known.begin(), known.end(), item.key()) != known.end()) continue;
    fail(keyPath(item.key()),
         cat("unknown key", didYouMean(item.key(), known), " (known: ", join(known, ", "), ")"));
  }
}

std::string indexPath(const std::string& path, size_t k) { return cat(path, "[", k, "]"); }

}  // namespace aperture::app
