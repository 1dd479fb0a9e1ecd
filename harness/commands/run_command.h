// `accelbench run` and `accelbench merge`: the YAML-driven side of the harness.
#pragma once

namespace accelbench {

// accelbench run [--dry-run] [--out FILE] [--resume] [--shard I/N] [--in-process]
//                [--show-repetitions] [--benchmark_out=FILE] [--benchmark_*...] CONFIG.yaml
// Exit codes: 0 all combinations ok, skipped or timed out; 1 some ended in error;
// 2 the config, the arguments or the output file are wrong (nothing was measured).
int run_command(int argc, char** argv);

// accelbench merge [--allow-mixed] [--config CONFIG.yaml [--shards N]] OUT.csv IN.csv...
// Exit codes: 0 merged; 2 bad input; 3 (--config) combinations of the config are in no
// input (nothing written).
int merge_command(int argc, char** argv);

}  // namespace accelbench
