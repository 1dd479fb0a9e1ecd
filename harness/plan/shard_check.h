// Whether shard files make a whole config: `accelbench merge --config CONFIG --shards N`.
// A Slurm task that failed, was cancelled or never started leaves its
// combinations in no input; a merge of the others must not pass for the whole run.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "plan/combinations.h"

namespace accelbench {

// The combinations of `all` whose combo_id is not in `present`, by the shard of `count`
// each belongs to (Shard::contains: hash % count).
std::map<uint64_t, std::vector<const Combination*>> missing_by_shard(const std::vector<Combination>& all,
                                                                     const std::set<std::string>& present,
                                                                     uint64_t count);

// Checks that the result files `inputs` hold every combination of the config, naming on
// stderr the missing ones by shard and the shards to run again (sbatch --array=<shards>).
// Returns 0 when complete, 3 when combinations are missing, 2 for bad input (a config
// that does not load, an unreadable CSV, a row whose combo_id is not of this config, an
// input a run is still writing, and unless allow_mixed an input whose record of inputs
// differs from what the config has now: another version of the config or its models).
int check_shards_complete(const std::string& config_path, uint64_t shards, const std::vector<std::string>& inputs,
                          bool allow_mixed = false);

}  // namespace accelbench
