#include "apps/batch/shard.h"

#include <cstdlib>
#include <optional>

#include "core/util/error.h"

namespace aperture::app {

namespace {

/// A decimal number of at most 9 digits (so it fits), or nothing.
std::optional<size_t> parseCount(const std::string& text) {
  if (text.empty() || text.size() > 9 || text.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  return size_t(std::stoul(text));
}

/// "NAME=value", or "NAME (unset)".
std::string showVariable(const EnvironmentLookup& env, const char* name) {
  const char* value = env(name);
  return value ? cat(name, "=", value) : cat(name, " (unset)");
}

/// An environment variable holding a non-negative integer; nothing when unset and optional.
std::optional<size_t> readVariable(const EnvironmentLookup& env, const char* name, bool required,
                                   const std::string& spec) {
  const char* value = env(name);
  if (!value) {
    if (!required) return std::nullopt;
    throw Error(cat("--shard ", spec, ": ", name, " is not set (is this a ",
                    spec == "slurm" ? "Slurm job array task?)" : "Kubernetes indexed Job?)"));
  }
  const std::optional<size_t> n = parseCount(value);
  if (!n) throw Error(cat("--shard ", spec, ": ", name, "='", value, "' is not a number >= 0"));
  return n;
}

Shard parseKOverN(const std::string& text) {
  const size_t slash = text.find('/');
  std::optional<size_t> k, n;
  if (slash != std::string::npos) {
    k = parseCount(text.substr(0, slash));
    n = parseCount(text.substr(slash + 1));
  }
  if (!k || !n || *n < 1 || *k >= *n)
    throw Error(cat("--shard: '", text,
                    "' must be K/N with 0 <= K < N (e.g. 0/4), slurm, or k8s/N (see --help)"));
  return Shard{*k, *n, ""};
}

Shard slurmShard(const EnvironmentLookup& env) {
  const char* kId = "SLURM_ARRAY_TASK_ID";
  const size_t id = *readVariable(env, kId, true, "slurm");
  const size_t count = *readVariable(env, "SLURM_ARRAY_TASK_COUNT", true, "slurm");
  const size_t min = *readVariable(env, "SLURM_ARRAY_TASK_MIN", true, "slurm");
  const size_t step = readVariable(env, "SLURM_ARRAY_TASK_STEP", false, "slurm").value_or(1);
  const std::optional<size_t> max = readVariable(env, "SLURM_ARRAY_TASK_MAX", false, "slurm");
  const std::string all = cat(
      showVariable(env, kId), ", ", showVariable(env, "SLURM_ARRAY_TASK_MIN"), ", ",
      showVariable(env, "SLURM_ARRAY_TASK_MAX"), ", ", showVariable(env, "SLURM_ARRAY_TASK_STEP"),
      ", ", showVariable(env, "SLURM_ARRAY_TASK_COUNT"));
  if (count < 1 || step < 1 || id < min || (id - min) % step != 0 || (id - min) / step >= count)
    throw Error(cat("--shard slurm: task ", id, " is not one of the ", count,
                    " tasks of the array (", all, ")"));
  if (max && *max != min + (count - 1) * step)
    throw Error(cat("--shard slurm: the array is not a range first-last[:step] (", all,
                    "); submit it as --array=0-", count - 1, " or give --shard K/N yourself"));
  return Shard{(id - min) / step, count, all};
}

Shard kubernetesShard(const std::string& text, const EnvironmentLookup& env) {
  const std::optional<size_t> n =
      text.size() > 4 ? parseCount(text.substr(4)) : std::optional<size_t>();
  if (!n || *n < 1)
    throw Error(cat("--shard: '", text,
                    "': give the Job's completions as k8s/N (N >= 1); Kubernetes does not "
                    "export it"));
  const size_t k = *readVariable(env, "JOB_COMPLETION_INDEX", true, "k8s");
  if (k >= *n)
    throw Error(cat("--shard ", text, ": JOB_COMPLETION_INDEX=", k, " is not below N = ", *n,
                    " (the Job's completions)"));
  return Shard{k, *n, cat("JOB_COMPLETION_INDEX=", k)};
}

}  // namespace

const char* processEnvironment(const char* name) { return std::getenv(name); }

Shard parseShard(const std::string& text, const EnvironmentLookup& env) {
  if (text.empty()) return Shard{};
  if (text == "slurm") return slurmShard(env);
  if (text == "k8s" || text.compare(0, 4, "k8s/") == 0) return kubernetesShard(text, env);
  return parseKOverN(text);
}

std::string unshardedSchedulerNote(const EnvironmentLookup& env) {
  if (env("SLURM_ARRAY_TASK_ID"))
    return cat(showVariable(env, "SLURM_ARRAY_TASK_ID"),
               " but no --shard: this task renders every image (use --shard slurm to split the "
               "job over the array)");
  if (env("JOB_COMPLETION_INDEX"))
    return cat(showVariable(env, "JOB_COMPLETION_INDEX"),
               " but no --shard: this pod renders every image (use --shard k8s/N to split the "
               "job over the Job's N completions)");
  return "";
}

}  // namespace aperture::app
