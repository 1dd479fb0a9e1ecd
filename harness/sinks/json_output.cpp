#include "sinks/json_output.h"

#include <iostream>
#include <stdexcept>

namespace accelbench {

JsonOutput::JsonOutput(const std::string& path) : file_(path, std::ios::trunc) {
    if (!file_) throw std::runtime_error("cannot open '" + path + "' for --benchmark_out");
    reporter_.SetOutputStream(&file_);
    reporter_.SetErrorStream(&std::cerr);
    benchmark::BenchmarkReporter::Context context;
    context.name_field_width = 0;
    reporter_.ReportContext(context);
    // Written through at once, so a file that takes no bytes (a full disk, /dev/full) is
    // refused before anything is measured, not found empty afterwards.
    file_.flush();
    if (!file_) throw std::runtime_error("cannot write '" + path + "' for --benchmark_out");
    path_ = path;
}

void JsonOutput::report(const CombinationResult& result) {
    const std::string& runs = result.measurement.json;
    if (runs.empty()) return;
    if (!first_) file_ << ",\n";
    file_ << runs;
    file_.flush();
    if (!file_) throw std::runtime_error("writing '" + path_ + "' for --benchmark_out failed");
    first_ = false;
}

// Also from the destructor: a run that ends early (an output that cannot be written)
// still leaves a JSON document.
void JsonOutput::finalize() {
    if (finalized_) return;
    finalized_ = true;
    reporter_.Finalize();
}

}  // namespace accelbench
