#include "sinks/repetitions_csv.h"

#include "util/text.h"

namespace accelbench {

void RepetitionsCsv::report(const CombinationResult& result) {
    const Measurement& m = result.measurement;
    if (!result.written() || m.status != "ok") return;
    const Combination& c = result.combination;
    const std::string params = c.params.canonical();
    for (size_t i = 0; i < m.render_s.size(); ++i)
        file_.append({{"config", config_name_},
                      {"combo_id", c.id},
                      {"model", result.model.label},
                      {"accel", c.accel},
                      {"params", params},
                      {"repetition", std::to_string(i + 1)},
                      {"build_s", number_text(m.build_s[i])},
                      {"render_s", number_text(m.render_s[i])},
                      {"process", std::to_string(m.process.empty() ? 1 : m.process[i])}});
}

}  // namespace accelbench
