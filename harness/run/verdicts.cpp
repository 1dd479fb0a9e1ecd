#include "run/verdicts.h"

#include <algorithm>

#include "accelbench/base/memory.h"
#include "accelbench/render/fp_mode.h"
#include "util/text.h"

namespace accelbench {

Measurement judge_measurement(const std::string& accel, const std::map<std::string, std::string>& given,
                              const RobustnessCase& c, const StageFn& stage) {
    reset_peak_rss();
    if (stage) stage("judging case " + c.id);
    // The catalogue's cases (denormal scales among them) are judged in IEEE mode, whatever
    // the config's render.fp_mode: its expectations are IEEE arithmetic's.
    const ScopedFpMode ieee(FpMode::Ieee);
    const CaseVerdict v = judge_case(c, accel, given);
    Measurement m;
    m.rays = v.rays;
    m.build.max_depth = v.max_depth;
    m.build.memory_bytes = v.memory_bytes;
    // A bad-input case is judged on its rejection at load: nothing was traced to compare.
    if (v.built) m.columns = error_columns(v.vs_reference, std::nullopt);
    m.columns["verdict"] = v.pass ? "pass" : "fail";
    m.columns["verdict_counts"] = v.counts();
    m.columns["peak_rss_bytes"] = std::to_string(peak_rss_bytes());
    m.message = v.detail;
    return m;
}

}  // namespace accelbench
