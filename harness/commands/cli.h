// The accelbench command line: one function per subcommand, each in its own file
// (commands/NAME_command.cpp), given the arguments after the subcommand's name and parsing
// them with the one argument parser (commands/args.h); returns the exit code. main.cpp
// holds the table of subcommands.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "accelbench/render/renderer.h"
#include "accelbench/scene/camera.h"
#include "accelbench/scene/scene.h"
#include "plan/loaded_model.h"

namespace accelbench {

class ModelRegistry;

// accelbench run [--dry-run[=json]] [--out FILE] [--resume] [--shard I/N] [--in-process]
//                [--show-repetitions] [--benchmark_out=FILE] [--benchmark_*...] CONFIG.yaml
// Exit codes: 0 all combinations ok, skipped or timed out; 1 some ended in error;
// 2 the config, the arguments or the output file are wrong (nothing was measured).
int run_command(int argc, char** argv);
// accelbench merge [--allow-mixed] [--config CONFIG.yaml [--shards N]] OUT.csv IN.csv...
// Exit codes: 0 merged; 2 bad input; 3 (--config) combinations of the config are in no
// input (nothing written).
int merge_command(int argc, char** argv);
int render_command(int argc, char** argv);
int list_command(int argc, char** argv);
int models_command(int argc, char** argv);
int provenance_command(int argc, char** argv);
int columns_command(int argc, char** argv);
int convert_csv_command(int argc, char** argv);

// `--plugin PATH` (run, list, render): loads each plugin into the registry; on a refusal
// prints "accelbench COMMAND: plugin PATH: problem" and returns 2, the exit code.
std::optional<int> load_plugins(const char* command, const std::vector<std::string>& paths);

// A command's exit status `status`, or 1 (after one line on stderr) when what it wrote to
// standard output did not all arrive: a full disk, or a closed pipe while SIGPIPE is
// ignored (a listing cut short is no success). main.cpp passes every command's status here.
int with_output_checked(const char* command, int status);

// NAME (registry), PATH (a mesh file) or procedural:KIND[,k=v...], loaded the way the
// harness loads a config's model (load_model: the registry's or procedural scene's own
// camera and light when it has one, else the auto-fit defaults for the image's aspect).
LoadedModel resolve_model(const std::string& spec, const ModelRegistry& registry, const RenderSettings& render);

}  // namespace accelbench
