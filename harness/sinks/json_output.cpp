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
}

void JsonOutput::report(const CombinationResult& result) {
    const std::string& runs = result.measurement.json;
    if (runs.empty()) return;
    if (!first_) file_ << ",\n";
    file_ << runs;
    file_.flush();
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
