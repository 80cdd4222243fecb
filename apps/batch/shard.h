#pragma once
// `aperture batch --shard`: which images of a job one process renders, given as K/N or read
// from the environment of a scheduler (Slurm job arrays, Kubernetes indexed Jobs).
#include <cstddef>
#include <functional>
#include <string>

namespace aperture::app {

/// Shard K of N renders the images whose index in job order is K modulo N.
struct Shard {
  size_t k = 0, n = 1;
  std::string origin;  ///< where K and N came from, for the log ("" when given as K/N)
  bool contains(size_t index) const { return index % n == k; }
};

/// Looks up an environment variable: its value, or nullptr when it is not set.
using EnvironmentLookup = std::function<const char*(const char* name)>;

/// The process environment (std::getenv).
const char* processEnvironment(const char* name);

/// Parses the value of --shard:
///  - "" : everything (0/1);
///  - "K/N" : 0 <= K < N;
///  - "slurm" : a Slurm job array, K = (SLURM_ARRAY_TASK_ID − SLURM_ARRAY_TASK_MIN) /
///    SLURM_ARRAY_TASK_STEP (step 1 when unset), N = SLURM_ARRAY_TASK_COUNT; the array must be a
///    range first-last[:step] (checked against SLURM_ARRAY_TASK_MAX when set);
///  - "k8s/N" : a Kubernetes indexed Job of N completions, K = JOB_COMPLETION_INDEX.
/// Throws Error naming --shard, or the variable and its value, for anything else.
Shard parseShard(const std::string& text, const EnvironmentLookup& env = processEnvironment);

/// When --shard is not given but a scheduler's index variable is set (every task would then
/// render the whole job): a note saying so and which --shard to use; "" otherwise.
std::string unshardedSchedulerNote(const EnvironmentLookup& env = processEnvironment);

}  // namespace aperture::app
