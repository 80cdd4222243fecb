// The per-ISA kernels of core/util/vector_kernel.h: which level APERTURE_KERNEL_ISA picks and
// refuses, that the command line runs the level it names, and that every level renders the
// same pixels bit for bit.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "core/aov/framebuffer.h"
#include "core/exr/exr.h"
#include "core/util/error.h"
#include "core/util/vector_kernel.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// The message of the Error chooseKernelIsa throws, or "" when it throws none.
std::string refusal(const char* value, KernelIsa cpu, KernelIsa built) {
  try {
    chooseKernelIsa(value, cpu, built);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// The levels this CPU and build can run, lowest first.
std::vector<KernelIsa> runnableLevels() {
  std::vector<KernelIsa> out;
  for (KernelIsa isa : {KernelIsa::Baseline, KernelIsa::V3, KernelIsa::V4})
    if (isa <= cpuKernelIsa() && isa <= builtKernelIsa()) out.push_back(isa);
  return out;
}

TEST(KernelIsa, UnsetPicksTheHighestLevelTheCpuAndTheBuildBothRun) {
  const KernelIsa b = KernelIsa::Baseline, v3 = KernelIsa::V3, v4 = KernelIsa::V4;
  EXPECT_EQ(chooseKernelIsa(nullptr, v4, v4), v4);
  EXPECT_EQ(chooseKernelIsa("", v4, v4), v4);
  EXPECT_EQ(chooseKernelIsa(nullptr, v3, v4), v3);
  EXPECT_EQ(chooseKernelIsa(nullptr, b, v4), b);
  EXPECT_EQ(chooseKernelIsa(nullptr, v4, b), b);
  // This process: what its environment, CPU and build give.
  EXPECT_EQ(activeKernelIsa(),
            chooseKernelIsa(std::getenv("APERTURE_KERNEL_ISA"), cpuKernelIsa(), builtKernelIsa()));
}

TEST(KernelIsa, EachNameForcesItsLevel) {
  const KernelIsa v4 = KernelIsa::V4;
  EXPECT_EQ(chooseKernelIsa("x86-64-v4", v4, v4), KernelIsa::V4);
  EXPECT_EQ(chooseKernelIsa("x86-64-v3", v4, v4), KernelIsa::V3);
  EXPECT_EQ(chooseKernelIsa("baseline", v4, v4), KernelIsa::Baseline);
  EXPECT_EQ(chooseKernelIsa("baseline", KernelIsa::Baseline, KernelIsa::Baseline),
            KernelIsa::Baseline);
  for (KernelIsa isa : {KernelIsa::Baseline, KernelIsa::V3, KernelIsa::V4})
    EXPECT_EQ(chooseKernelIsa(kernelIsaName(isa), v4, v4), isa);
}

TEST(KernelIsa, AnUnknownOrUnrunnableLevelIsAnErrorNamingTheVariableAndTheValue) {
  const KernelIsa b = KernelIsa::Baseline, v3 = KernelIsa::V3, v4 = KernelIsa::V4;
  const std::string typo = refusal("x86-64-v5", v4, v4);
  EXPECT_NE(typo.find("APERTURE_KERNEL_ISA=x86-64-v5"), std::string::npos) << typo;
  EXPECT_NE(typo.find("did you mean 'x86-64-v4'?"), std::string::npos) << typo;
  EXPECT_NE(refusal("baselin", v4, v4).find("did you mean 'baseline'?"), std::string::npos);
  EXPECT_NE(refusal("avx2", v4, v4).find("known: x86-64-v4, x86-64-v3, baseline"),
            std::string::npos);
  EXPECT_NE(refusal("X86-64-V3", v4, v4), "");  // names are exact
  const std::string cpu = refusal("x86-64-v4", v3, v4);
  EXPECT_NE(cpu.find("APERTURE_KERNEL_ISA=x86-64-v4"), std::string::npos) << cpu;
  EXPECT_NE(cpu.find("cannot run"), std::string::npos) << cpu;
  EXPECT_NE(cpu.find("up to x86-64-v3"), std::string::npos) << cpu;
  EXPECT_NE(refusal("x86-64-v3", b, v4).find("up to baseline"), std::string::npos);
  const std::string build = refusal("x86-64-v3", v4, b);
  EXPECT_NE(build.find("APERTURE_KERNEL_ISA=x86-64-v3"), std::string::npos) << build;
  EXPECT_NE(build.find("baseline only"), std::string::npos) << build;
}

TEST(KernelIsa, TheCommandLineRunsTheLevelTheVariableNamesAndRefusesABadOne) {
  for (KernelIsa isa : runnableLevels()) {
    const std::string json = test::scratchDir() + "/bench_" + kernelIsaName(isa) + ".json";
    std::string out;
    ASSERT_EQ(test::runCommand(std::string("APERTURE_KERNEL_ISA=") + kernelIsaName(isa) + " " +
                                   test::apertureBinary() +
                                   " bench --size 16,16 --frames 1 --warmup 0 --builds 1 "
                                   "--mesh procedural:sphere --json " +
                                   json,
                               &out),
              0)
        << out;
    EXPECT_NE(test::readFile(json).find(std::string("\"kernel_isa\": \"") + kernelIsaName(isa)),
              std::string::npos)
        << test::readFile(json);
    EXPECT_NE(out.find(std::string("kernels ") + kernelIsaName(isa) + ";"), std::string::npos)
        << out;
  }
  std::string out;
  EXPECT_NE(test::runCommand("APERTURE_KERNEL_ISA=x86-64-v9 " + test::apertureBinary() +
                                 " render --size 8,8 --out " + test::scratchDir() + "/bad.exr",
                             &out),
            0);
  EXPECT_NE(out.find("APERTURE_KERNEL_ISA=x86-64-v9"), std::string::npos) << out;
  EXPECT_NE(out.find("did you mean"), std::string::npos) << out;
}

TEST(KernelIsa, EveryLevelRendersTheSamePixels) {
  // The kernels' rule (core/util/vector_kernel.h): the same bits on every level. Embree's kernels
  // pinned, so only aperture's differ: ray generation of three camera models, the frame loop's
  // stores (every AOV) and the mesh placement. Compared AOV by AOV, bit for bit.
  const std::vector<KernelIsa> levels = runnableLevels();
  if (levels.size() < 2) GTEST_SKIP() << "this CPU or build runs only the baseline kernels";
  for (const char* camera :
       {"--camera thinlens --aperture 0.2 --focus 15 --spp 4", "--camera fisheye",
        "--intrinsics 40,40,30,18 --lens-model OPENCV --distortion 0.1,0.01,0.001,0.001"}) {
    std::vector<Framebuffer> images;
    for (KernelIsa isa : levels) {
      const std::string path = test::scratchDir() + "/level_" + kernelIsaName(isa) + ".exr";
      std::string out;
      ASSERT_EQ(test::runCommand(std::string("APERTURE_EMBREE_CONFIG=isa=sse4.2 "
                                             "APERTURE_KERNEL_ISA=") +
                                     kernelIsaName(isa) + " " + test::apertureBinary() +
                                     " render --mesh procedural:city " + camera +
                                     " --eye 14,11,18 --at 0,1,0 --size 61,37 --aov all "
                                     "--quiet --out " +
                                     path,
                                 &out),
                0)
          << out;
      images.push_back(readExr(path));
    }
    for (size_t k = 1; k < images.size(); ++k)
      test::expectIdentical(images[k], images[0],
                            std::string(camera) + ": " + kernelIsaName(levels[k]) + " against " +
                                kernelIsaName(levels[0]));
  }
}

}  // namespace
}  // namespace aperture
