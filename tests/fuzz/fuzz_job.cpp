// libFuzzer target: the batch job reader (JSON, one scene or "scenes", validation, camera
// construction) on arbitrary text. Mesh paths resolve against a directory that does not exist, so
// nothing is loaded.
#include <cstddef>
#include <cstdint>
#include <string>

#include "apps/jobs/job.h"
#include "core/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    aperture::app::readJobFileText(std::string(reinterpret_cast<const char*>(data), size),
                                   "fuzz.json", "/nonexistent-aperture-fuzz");
  } catch (const aperture::Error&) {
    // A clear error is the right answer to a malformed job.
  }
  return 0;
}
