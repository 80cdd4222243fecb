#include "core/util/vector_kernel.h"

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

namespace {

constexpr const char* kVariable = "APERTURE_KERNEL_ISA";

const KernelIsa kLevels[] = {KernelIsa::V4, KernelIsa::V3, KernelIsa::Baseline};

}  // namespace

const char* kernelIsaName(KernelIsa isa) {
  switch (isa) {
    case KernelIsa::V4:
      return "x86-64-v4";
    case KernelIsa::V3:
      return "x86-64-v3";
    case KernelIsa::Baseline:
      break;
  }
  return "baseline";
}

KernelIsa cpuKernelIsa() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("x86-64-v4")) return KernelIsa::V4;
  if (__builtin_cpu_supports("x86-64-v3")) return KernelIsa::V3;
#endif
  return KernelIsa::Baseline;
}

KernelIsa builtKernelIsa() { return APERTURE_ISA_CLONES ? KernelIsa::V4 : KernelIsa::Baseline; }

KernelIsa chooseKernelIsa(const char* value, KernelIsa cpu, KernelIsa built) {
  const KernelIsa best = std::min(cpu, built);
  if (!value || !*value) return best;
  const std::string given(value);
  std::vector<std::string> names;
  for (KernelIsa isa : kLevels) {
    names.push_back(kernelIsaName(isa));
    if (given != names.back()) continue;
    if (isa > built)
      throw Error(cat(kVariable, "=", given,
                      ": this build compiled its kernels for the baseline only (a sanitizer, "
                      "fuzz or non-GCC build); use baseline or unset it"));
    if (isa > cpu)
      throw Error(cat(kVariable, "=", given, ": this CPU cannot run ", given,
                      " code (it runs up to ", kernelIsaName(cpu), ")"));
    return isa;
  }
  throw Error(cat(kVariable, "=", given, ": unknown kernel level", didYouMean(given, names),
                  " (known: x86-64-v4, x86-64-v3, baseline)"));
}

KernelIsa activeKernelIsa() {
  static const KernelIsa active =
      chooseKernelIsa(std::getenv(kVariable), cpuKernelIsa(), builtKernelIsa());
  return active;
}

}  // namespace aperture
