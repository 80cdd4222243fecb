#pragma once
// `aperture batch --merge-summaries OUT.json IN...`: one summary for a job rendered in shards,
// naming the images that no shard rendered.
#include <string>
#include <vector>

namespace aperture::app {

/// Merges the per-image entries of `inputs` (summary.json files of `aperture batch`, or earlier
/// merges) into `outPath`, written atomically. All inputs must be summaries of one job (the
/// same "job" path and "images_in_job"), else Error names the two files that differ. For each
/// image index the best entry wins (ok or skipped, then failed, then interrupted; the first
/// input on a tie). An image is done when its entry is ok or skipped (a --resume run found its
/// output complete and matching the job); every other image of the job is missing: listed in
/// "missing" (named "camera frame N", from the entries or, for images no input lists, from
/// the job file when it can be read) and on stderr unless `quiet`. Returns 0 when nothing is
/// missing, 1 otherwise. Throws Error for an unreadable or malformed input.
int mergeSummaries(const std::string& outPath, const std::vector<std::string>& inputs, bool quiet);

}  // namespace aperture::app
