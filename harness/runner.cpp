#include "runner.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "accelbench/accel/registry.h"
#include "loaded_model.h"
#include "measure.h"
#include "text.h"
#include "verdicts.h"

namespace accelbench {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// A config model as the run needs it: its sizes when known without loading, the loaded
// model on first need, the reference's answers on first measurement. A model that does
// not load is bad input: its combinations get no rows at all.
class ModelOnDemand {
public:
    ModelOnDemand(const ModelSpec& spec, const RunPlan& plan, bool reference_wanted, bool in_process)
        : spec_(spec), plan_(plan), reference_wanted_(reference_wanted), in_process_(in_process) {
        triangles = known_triangles(spec, plan.registry);
        if (const ModelEntry* entry = spec.kind == ModelSpec::Kind::Registry ? plan.registry.find(spec.name) : nullptr)
            vertices = entry->vertices;
        if (!triangles && load()) triangles = loaded_->scene.triangle_count(), vertices = loaded_->scene.vertex_count();
    }

    // The model, loaded if it was not; nullptr (and load_error) when it does not load.
    const LoadedModel* load() {
        if (!loaded_ && load_error.empty()) {
            const auto t0 = Clock::now();
            try {
                loaded_ = load_model(spec_, plan_.registry, plan_.config.render);
                std::fprintf(stderr, "accelbench run: loaded %s: %zu triangles, %zu vertices in %.2f s\n",
                             spec_.label.c_str(), loaded_->scene.triangle_count(), loaded_->scene.vertex_count(),
                             seconds_since(t0));
            } catch (const std::exception& e) {
                load_error = e.what();
                std::fprintf(stderr, "accelbench run: cannot load %s: %s\n", spec_.label.c_str(), e.what());
            }
        }
        return loaded_ ? &*loaded_ : nullptr;
    }

    // The reference's answers, once per model, before its first measurement (not for a
    // robustness case, which brings its own). Traced in a child process under the
    // config's timeout_s, like each measurement (unless --in-process). False (and
    // reference_error, or reference_timeout) when the reference cannot trace the model.
    bool add_reference() {
        // Ray sets need the reference's answers to be made at all, `errors` or not.
        const bool wanted = reference_wanted_ || plan_.config.ray_sets;
        if (!wanted || loaded_->robustness_case || loaded_->reference || !reference_error.empty() ||
            !reference_timeout.empty())
            return reference_error.empty() && reference_timeout.empty();
        try {
            // Made here, in the parent process (single-threaded), outside anything timed.
            if (plan_.config.ray_sets && !loaded_->ray_sets)
                add_ray_sets(*loaded_, plan_.config.render, *plan_.config.ray_sets);
            if (in_process_) add_reference_answers(*loaded_, plan_.config.render);
            else trace_reference_in_child();
        } catch (const std::exception& e) {
            reference_error = e.what();
        }
        if (!reference_timeout.empty())
            std::fprintf(stderr, "accelbench run: the reference pass of %s: %s\n", spec_.label.c_str(),
                         reference_timeout.c_str());
        else if (!reference_error.empty())
            std::fprintf(stderr, "accelbench run: the reference cannot trace %s: %s\n", spec_.label.c_str(),
                         reference_error.c_str());
        else
            std::fprintf(stderr, "accelbench run: reference answers for %s: %zu primary rays in %.2f s\n",
                         spec_.label.c_str(), loaded_->reference->hits.size(), loaded_->reference->seconds);
        return reference_error.empty() && reference_timeout.empty();
    }

    std::optional<uint64_t> triangles, vertices;
    std::string load_error, reference_error, reference_timeout;

private:
    // The reference pass counts against timeout_s as a combination's measurement does:
    // a model whose reference cannot finish in time gets timeout rows, not an unbounded wait.
    void trace_reference_in_child() {
        const double limit = plan_.config.timeout_s;
        const ChildOutcome o = run_in_child(
            [&](const StageFn& stage) -> std::string {
                stage("the reference pass");
                try {
                    add_reference_answers(*loaded_, plan_.config.render);
                    return concat("A", reference_bytes(*loaded_->reference));
                } catch (const std::exception& e) {
                    return concat("E", e.what());
                }
            },
            limit);
        if (o.timed_out)
            reference_timeout =
                time_limit_message(limit, "the reference pass (once per model, before its measurements)");
        else if (!o.result) reference_error = "the reference process " + o.failure;
        else if (o.result->rfind("E", 0) == 0) reference_error = o.result->substr(1);
        else loaded_->reference = reference_from_bytes(o.result->substr(1));
    }

    const ModelSpec& spec_;
    const RunPlan& plan_;
    const bool reference_wanted_, in_process_;
    std::optional<LoadedModel> loaded_;
};

class Runner {
public:
    Runner(const RunPlan& plan, const RunOptions& options) : plan_(plan), options_(options) {}

    // One combination: skipped by a rule, not run (its model did not load), an error
    // without measuring (the reference cannot trace the model), or measured.
    CombinationResult run_one(const Combination& c, ModelOnDemand& model) {
        const ModelSpec& spec = plan_.config.models[c.model];
        CombinationResult r{c, spec, model.triangles, model.vertices, utc_now("%Y-%m-%dT%H:%M:%SZ"), "", {}, {}};
        if (auto reason = model.triangles ? skip_reason(plan_.config, c, *model.triangles) : std::nullopt) {
            r.measurement.status = "skipped";
            r.measurement.message = *reason;
        } else if (const LoadedModel* loaded = model.load(); !loaded) {
            r.load_error = model.load_error;
        } else if (!model.add_reference()) {
            r.measurement.status = model.reference_timeout.empty() ? "error" : "timeout";
            r.measurement.message = model.reference_timeout.empty()
                ? "no error measurement: the reference cannot trace the model: " + model.reference_error
                : model.reference_timeout;
        } else {
            const auto t0 = Clock::now();
            r.measurement = measure_combination(c, *loaded);
            r.measuring_s = seconds_since(t0);
        }
        return r;
    }

private:
    // Timed (or judged, for a robustness case) in a child process that the time limit can
    // stop, unless --in-process.
    Measurement measure_combination(const Combination& c, const LoadedModel& model) {
        const AcceleratorInfo* info = find_accelerator(c.accel);
        MeasureSettings ms;
        ms.repetitions = repetitions_of(plan_.config, c);
        ms.warmup = warmup_of(plan_.config, c);
        ms.show_repetitions = options_.show_repetitions;
        ms.show_context = first_measurement_;
        ms.json = !options_.json_out.empty();
        ms.timeout_s = plan_.config.timeout_s;
        ms.callgrind_out = options_.callgrind_out;
        ms.callgrind_tag = c.id;
        if (!options_.callgrind_out.empty()) {
            // Under valgrind times are not measurements and every render is slow: one
            // counted repetition (the counted one), the counting render as warm-up.
            ms.repetitions = 1;
            ms.warmup = std::min(ms.warmup, 1);
        }
        first_measurement_ = false;
        auto work = [&](const StageFn& stage) {
            if (model.robustness_case) return judge_measurement(c.accel, c.given, *model.robustness_case, stage);
            return measure(c.name, *info, c.params, model, render_of(plan_.config, c), ms, stage, c.ray_set);
        };
        return options_.in_process ? work(StageFn{}) : run_isolated(work, plan_.config.timeout_s);
    }

    const RunPlan& plan_;
    const RunOptions& options_;
    bool first_measurement_ = true;  // Google Benchmark's machine description is shown once
};

}  // namespace

int run_plan(const RunPlan& plan, const RunOptions& options, const std::vector<RunSink*>& sinks) {
    const RunContext context{
        plan.config,      plan.out, plan.shard, plan.selected.size(), plan.selected.size() - plan.to_do.size(),
        plan.to_do.size()};
    for (RunSink* s : sinks) s->context(context);
    // Not under callgrind, whose instruction counts are the point of such a run.
    const bool reference_wanted = plan.config.errors && options.callgrind_out.empty();
    Runner runner(plan, options);
    bool not_loaded = false, errors = false;
    for (size_t mi = 0; mi < plan.config.models.size(); ++mi) {
        std::vector<const Combination*> mine;
        std::copy_if(plan.to_do.begin(), plan.to_do.end(), std::back_inserter(mine),
                     [&](const Combination* c) { return c->model == mi; });
        if (mine.empty()) continue;
        ModelOnDemand model(plan.config.models[mi], plan, reference_wanted, options.in_process);
        for (const Combination* c : mine) {
            for (RunSink* s : sinks) s->starting(*c);
            const CombinationResult result = runner.run_one(*c, model);
            not_loaded |= !result.written();
            errors |= result.written() && result.measurement.status == "error";
            try {
                for (RunSink* s : sinks) s->report(result);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "accelbench run: %s\n", e.what());
                return 2;
            }
        }
    }
    for (RunSink* s : sinks) s->finalize();
    return not_loaded ? 2 : errors ? 1 : 0;
}

}  // namespace accelbench
