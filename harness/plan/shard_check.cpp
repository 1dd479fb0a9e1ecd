#include "plan/shard_check.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "config/config.h"
#include "csv/csv.h"
#include "models/model_registry.h"
#include "plan/combinations.h"
#include "plan/run_plan.h"
#include "util/output_lock.h"
#include "util/text.h"

namespace accelbench {

std::map<uint64_t, std::vector<const Combination*>> missing_by_shard(const std::vector<Combination>& all,
                                                                     const std::set<std::string>& present,
                                                                     uint64_t count) {
    std::map<uint64_t, std::vector<const Combination*>> missing;
    for (const auto& c : all)
        if (!present.count(c.id)) missing[c.hash % count].push_back(&c);
    return missing;
}

int check_shards_complete(const std::string& config_path, uint64_t shards, const std::vector<std::string>& inputs,
                          bool allow_mixed) {
    std::vector<Combination> all;
    std::set<std::string> present;
    try {
        const ModelRegistry registry = ModelRegistry::load_default();
        const Config config = load_config(config_path, registry);
        all = expand(config);
        if (!allow_mixed) {
            const RunInputs now = inputs_of(config, registry);
            for (const auto& in : inputs)
                if (const auto recorded = read_inputs(in))
                    if (const std::string d = inputs_differences(*recorded, in, now, config_path); !d.empty())
                        throw std::runtime_error(in + " was measured from other contents than " + config_path +
                                                 " has now (" + d + "); pass --allow-mixed to merge it anyway");
        }
        std::set<std::string> expected;
        for (const auto& c : all) expected.insert(c.id);
        for (const auto& in : inputs) {
            const InputLock locked({in});  // a shard still running is not missing its rows
            const CsvData d = read_csv(in);
            const auto col = std::find(d.header.begin(), d.header.end(), "combo_id");
            if (col == d.header.end()) throw std::runtime_error(in + ": no combo_id column");
            for (const auto& r : d.rows) {
                const std::string& id = r[size_t(col - d.header.begin())];
                if (!expected.count(id))
                    throw std::runtime_error(in + ": combination " + id + " is not in " + config_path +
                                             " (a shard of another config, or of another build?)");
                present.insert(id);
            }
        }
    } catch (const ConfigError& e) {
        for (const auto& issue : e.issues()) std::fprintf(stderr, "%s\n", format_issue(issue).c_str());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench merge: %s\n", e.what());
        return 2;
    }
    const auto missing = missing_by_shard(all, present, shards);
    if (missing.empty()) return 0;
    size_t n = 0;
    std::string ids;
    for (const auto& [shard, combos] : missing) {
        n += combos.size();
        append_item(ids, ",", std::to_string(shard));
    }
    std::fprintf(stderr,
                 "accelbench merge: incomplete: %zu of the %zu combinations of %s are in no input; nothing "
                 "written. Missing, by shard of %llu:\n",
                 n, all.size(), config_path.c_str(), (unsigned long long)shards);
    for (const auto& [shard, combos] : missing) {
        std::fprintf(stderr, "  shard %llu: %zu missing:", (unsigned long long)shard, combos.size());
        for (size_t i = 0; i < combos.size() && i < 3; ++i) std::fprintf(stderr, " %s", combos[i]->name.c_str());
        std::fprintf(stderr, "%s\n", combos.size() > 3 ? " ..." : "");
    }
    std::fprintf(stderr,
                 "accelbench merge: run shards %s again (--shard I/%llu --resume; under Slurm "
                 "--array=%s) and merge again\n",
                 ids.c_str(), (unsigned long long)shards, ids.c_str());
    return 3;
}

}  // namespace accelbench
