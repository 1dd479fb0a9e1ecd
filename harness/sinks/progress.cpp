#include "sinks/progress.h"

#include <algorithm>

#include "util/text.h"

namespace accelbench {

namespace {

// h:mm:ss, or m:ss under an hour.
std::string clock_text(double s) {
    const long t = long(s + 0.5);
    char buf[32];
    if (t >= 3600) std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    else std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
    return buf;
}

}  // namespace

void Progress::context(const RunContext& c) {
    config_name_ = c.config.name;
    out_path_ = c.out;
    to_do_ = c.to_do;
    const std::string in_shard = c.shard && c.shard->count > 1
        ? " in shard " + std::to_string(c.shard->index) + "/" + std::to_string(c.shard->count)
        : "";
    std::fprintf(out_, "accelbench run: %s: %zu combinations%s, %zu already in %s, %zu to go\n", config_name_.c_str(),
                 c.selected, in_shard.c_str(), c.already_done, out_path_.c_str(), c.to_do);
    start_ = Clock::now();
}

void Progress::starting(const Combination& c) {
    ++begun_;
    const std::string eta = measured_
        ? ", about " + clock_text(measured_s_ / double(measured_) * double(to_do_ - begun_ + 1)) + " left"
        : "";
    std::fprintf(out_, "[%zu/%zu] %s  (elapsed %s%s)\n", begun_, to_do_, c.name.c_str(),
                 clock_text(elapsed_s()).c_str(), eta.c_str());
}

void Progress::report(const CombinationResult& r) {
    if (r.measuring_s) {
        measured_s_ += *r.measuring_s;
        ++measured_;
    }
    if (!r.written()) {
        ++not_written_;
        const std::string u = r.model.label + ": " + r.load_error;
        if (std::find(unloadable_.begin(), unloadable_.end(), u) == unloadable_.end()) unloadable_.push_back(u);
        return;
    }
    const Measurement& m = r.measurement;
    ++by_status_[m.status];
    if (m.status != "ok")
        std::fprintf(out_, "[%zu/%zu] %s: %s%s%s\n", begun_, to_do_, r.combination.name.c_str(), m.status.c_str(),
                     m.message.empty() ? "" : ": ", m.message.c_str());
}

void Progress::finalize() {
    std::string counts;
    for (const auto& [s, n] : by_status_) append_item(counts, ", ", std::to_string(n), " ", s);
    std::fprintf(out_, "accelbench run: %s: %zu rows written to %s (%s) in %s\n", config_name_.c_str(),
                 begun_ - not_written_, out_path_.c_str(), counts.empty() ? "nothing to do" : counts.c_str(),
                 clock_text(elapsed_s()).c_str());
    if (unloadable_.empty()) return;
    for (const auto& u : unloadable_) std::fprintf(out_, "accelbench run: cannot load %s\n", u.c_str());
    std::fprintf(out_,
                 "accelbench run: %zu combination%s not run and not written: %zu model%s did not load "
                 "(fix and rerun with --resume)\n",
                 not_written_, not_written_ == 1 ? "" : "s", unloadable_.size(), unloadable_.size() == 1 ? "" : "s");
}

}  // namespace accelbench
