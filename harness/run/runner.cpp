#include "run/runner.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iterator>
#include <map>
#include <utility>

#include "accelbench/accel/registry.h"
#include "accelbench/base/unknown_name.h"
#include "plan/loaded_model.h"
#include "run/child_process.h"
#include "run/measure.h"
#include "run/verdicts.h"
#include "util/text.h"
#include "util/wire.h"

namespace accelbench {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// A config model as the run needs it: its sizes when known without loading, the prepared
// model on first need. A model that does not load is bad input: its combinations get no
// rows at all.
//
// Preparing a model is loading it (reading and checking the mesh, a derived model's
// transform, procedural generation), making its ray sets and tracing the reference's
// answers, once per model, before its first measurement. It runs in one child process under
// the config's timeout_s, like each measurement (unless --in-process), and comes back to
// the parent in the wire form (util/wire.h): a model whose preparation cannot finish in time
// gets timeout rows naming the stage, never an unbounded wait in the parent. A robustness
// case (a small generated scene that brings its own reference answers) is made in the parent.
class ModelOnDemand {
public:
    ModelOnDemand(const ModelSpec& spec, const RunPlan& plan, std::vector<const Combination*> combinations,
                  bool reference_wanted, bool in_process)
        : spec_(spec),
          plan_(plan),
          combinations_(std::move(combinations)),
          reference_wanted_(reference_wanted),
          in_process_(in_process) {
        triangles = known_triangles(spec, plan.registry);
        if (const ModelEntry* entry = spec.kind == ModelSpec::Kind::Registry ? plan.registry.find(spec.name) : nullptr)
            vertices = entry->vertices;
        // The skip rules need the count: the model is prepared now.
        if (!triangles) prepare();
    }

    // The prepared model, prepared if it was not; nullptr when it is not there: load_error
    // (it does not load) or timeout (its preparation passed the deadline).
    const LoadedModel* prepare() {
        if (prepared_) return loaded_ ? &*loaded_ : nullptr;
        prepared_ = true;
        if (in_process_ || spec_.kind == ModelSpec::Kind::Case) take(prepare_here({}));
        else prepare_in_child();
        if (!timeout.empty())
            std::fprintf(stderr, "accelbench run: preparing %s: %s\n", spec_.label.c_str(), timeout.c_str());
        else if (!load_error.empty())
            std::fprintf(stderr, "accelbench run: cannot load %s: %s\n", spec_.label.c_str(), load_error.c_str());
        else if (!reference_error.empty())
            std::fprintf(stderr, "accelbench run: the reference cannot trace %s: %s\n", spec_.label.c_str(),
                         reference_error.c_str());
        else if (loaded_->reference)
            std::fprintf(stderr, "accelbench run: reference answers for %s: %zu primary rays in %.2f s\n",
                         spec_.label.c_str(), loaded_->reference->hits.size(), loaded_->reference->seconds);
        if (loaded_ && !triangles)
            triangles = loaded_->scene.triangle_count(), vertices = loaded_->scene.vertex_count();
        return loaded_ ? &*loaded_ : nullptr;
    }

    // The prepared model as it is now, without preparing it.
    const LoadedModel* loaded() const { return loaded_ ? &*loaded_ : nullptr; }

    std::optional<uint64_t> triangles, vertices;
    // Why the model has no rows; why the reference cannot trace it; which stage of its
    // preparation passed the deadline.
    std::string load_error, reference_error, timeout;

private:
    // The model, or why there is none, and why the reference cannot trace it.
    struct Preparation {
        std::optional<LoadedModel> model;
        std::string load_error, reference_error;
    };

    static constexpr const char* reference_stage = "the reference pass (once per model, before its measurements)";

    std::string loading_stage() const { return concat("loading ", spec_.label); }

    // Every stage of preparing, in this process; `stage` hears each one begin.
    Preparation prepare_here(const StageFn& stage) const {
        Preparation p;
        if (stage) stage(loading_stage());
        const auto t0 = Clock::now();
        try {
            if (std::string changed = model_file_changed(plan_, spec_); !changed.empty()) {
                p.load_error = std::move(changed);
                return p;
            }
            p.model = load_model(spec_, plan_.registry, plan_.config.render);
        } catch (const std::exception& e) {
            p.load_error = e.what();
            return p;
        }
        std::fprintf(stderr, "accelbench run: loaded %s: %zu triangles, %zu vertices in %.2f s\n", spec_.label.c_str(),
                     p.model->scene.triangle_count(), p.model->scene.vertex_count(), seconds_since(t0));
        if (!reference_needed(*p.model)) return p;
        try {
            // Single-threaded, outside anything timed.
            if (plan_.config.ray_sets) {
                if (stage) stage("making the ray sets (once per model, before its measurements)");
                add_ray_sets(*p.model, plan_.config.render, *plan_.config.ray_sets);
            }
            if (stage) stage(reference_stage);
            add_reference_answers(*p.model, plan_.config.render);
        } catch (const std::exception& e) {
            p.reference_error = e.what();
        }
        return p;
    }

    // The reference's answers (and the ray sets, which need them to be made at all, `errors`
    // or not) are made when a combination on the model will be measured: not for a
    // robustness case, which brings its own, nor when the skip rules skip every one.
    bool reference_needed(const LoadedModel& m) const {
        if ((!reference_wanted_ && !plan_.config.ray_sets) || m.robustness_case) return false;
        return std::any_of(combinations_.begin(), combinations_.end(), [&](const Combination* c) {
            return !skip_reason(plan_.config, *c, m.scene.triangle_count());
        });
    }

    void take(Preparation p) {
        if (p.model) loaded_ = std::move(*p.model);
        load_error = std::move(p.load_error);
        reference_error = std::move(p.reference_error);
    }

    // The child's answer, in the wire form: whether a model follows, why the model does not
    // load, why the reference cannot trace it (each empty when it can), then the model.
    void prepare_in_child() {
        const double limit = plan_.config.timeout_s;
        const ChildOutcome o = run_in_child(
            [&](const StageFn& stage) -> std::string {
                WireWriter w;
                try {
                    Preparation p = prepare_here(stage);
                    w.put(uint8_t(p.model.has_value()));
                    w.put_string(p.load_error);
                    w.put_string(p.reference_error);
                    if (p.model) put_loaded_model(w, *p.model);
                } catch (const std::exception& e) {  // the model does not fit into bytes (bad_alloc)
                    w = WireWriter();
                    w.put(uint8_t(0));
                    w.put_string(concat("cannot bring the prepared model to the parent process: ", e.what()));
                    w.put_string("");
                }
                return w.take();
            },
            limit, loading_stage());
        if (o.timed_out) {
            timeout = time_limit_message(limit, o.stage);
        } else if (!o.result) {
            // A crash is a bug of ours, not bad input; while loading it still leaves no model.
            const std::string why = concat("the process preparing the model ", o.failure, " during ", o.stage);
            if (o.stage == loading_stage()) load_error = why;
            else reference_error = why;
        } else {
            try {
                WireReader r(*o.result, "prepared model");
                const bool has_model = r.take<uint8_t>();
                load_error = r.take_string();
                reference_error = r.take_string();
                if (has_model) loaded_ = take_loaded_model(r, spec_);
                r.expect_end();
            } catch (const std::exception& e) {  // a bug of ours: no model, no rows
                loaded_.reset();
                load_error = concat("the prepared model came back damaged from its process: ", e.what());
            }
        }
    }

    const ModelSpec& spec_;
    const RunPlan& plan_;
    const std::vector<const Combination*> combinations_;
    const bool reference_wanted_, in_process_;
    bool prepared_ = false;
    std::optional<LoadedModel> loaded_;
};

class Runner {
public:
    Runner(const RunPlan& plan, const RunOptions& options) : plan_(plan), options_(options) {}

    // One combination's result before measuring: skipped by a rule, a timeout (its model's
    // preparation passed the deadline), not run (its model did not load), an error without
    // measuring (the reference cannot trace the model); `to_measure` when none of these.
    CombinationResult unmeasured(const Combination& c, ModelOnDemand& model, bool& to_measure) {
        const ModelSpec& spec = plan_.config.models[c.model];
        CombinationResult r{c, spec, model.triangles, model.vertices, utc_now("%Y-%m-%dT%H:%M:%SZ"), "", {}, {}};
        to_measure = false;
        if (auto reason = model.triangles ? skip_reason(plan_.config, c, *model.triangles) : std::nullopt) {
            r.measurement.status = "skipped";
            r.measurement.message = *reason;
        } else if (const LoadedModel* loaded = model.prepare(); !loaded && !model.timeout.empty()) {
            r.measurement.status = "timeout";
            r.measurement.message = model.timeout;
        } else if (!loaded) {
            r.load_error = model.load_error;
        } else if (auto failed = c.ray_set ? loaded->ray_set_errors.find(*c.ray_set) : loaded->ray_set_errors.end();
                   failed != loaded->ray_set_errors.end()) {
            r.measurement.status = "error";
            r.measurement.message =
                "ray set '" + std::string(ray_set_name(*c.ray_set)) + "' cannot be made: " + failed->second;
        } else if (!model.reference_error.empty()) {
            r.measurement.status = "error";
            r.measurement.message =
                "no error measurement: the reference cannot trace the model: " + model.reference_error;
        } else {
            to_measure = true;
        }
        return r;
    }

    // The combinations of `group` (one model's, timed together when the config interleaves),
    // each skipped, failed before measuring (unmeasured) or measured in process 1.
    std::vector<CombinationResult> run_group(const std::vector<const Combination*>& group, ModelOnDemand& model) {
        std::vector<CombinationResult> results;
        std::vector<size_t> measured;
        for (const Combination* c : group) {
            bool to_measure = false;
            results.push_back(unmeasured(*c, model, to_measure));
            if (to_measure) measured.push_back(results.size() - 1);
        }
        if (!measured.empty()) measure_into(results, measured, *model.loaded(), 1);
        return results;
    }

    // How many processes measure a combination: its `processes` (processes_of), one under
    // callgrind (whose count is of one render) and --in-process (there is no other process).
    int processes(const Combination& c) const {
        return options_.in_process || !options_.callgrind_out.empty() ? 1 : processes_of(plan_.config, c);
    }

    // The group measured again in process `process` (2 and up), each result pooled into its
    // own: only the measured combinations that are ok so far and have that many processes,
    // never a robustness case.
    void measure_again(std::vector<CombinationResult>& group, const ModelOnDemand& model, int process) {
        const LoadedModel* loaded = model.loaded();
        if (!loaded || loaded->robustness_case) return;
        std::vector<size_t> again;
        for (size_t i = 0; i < group.size(); ++i)
            if (process <= processes(group[i].combination) && group[i].measurement.status == "ok" &&
                group[i].measuring_s)
                again.push_back(i);
        measure_into(group, again, *loaded, process);
    }

    // The groups a model's combinations are timed in, in the plan's order: with
    // `interleave`, those that trace the same rays (ray set and render thread count)
    // together; alone otherwise, under callgrind (whose count is of one render) and for a
    // robustness case (judged, not timed).
    std::vector<std::vector<const Combination*>> groups(const std::vector<const Combination*>& mine,
                                                        const ModelSpec& spec) const {
        std::vector<std::vector<const Combination*>> out;
        const bool together =
            plan_.config.interleave && options_.callgrind_out.empty() && spec.kind != ModelSpec::Kind::Case;
        std::map<std::pair<std::optional<RaySetKind>, int>, size_t> index;
        for (const Combination* c : mine) {
            if (!together) {
                out.push_back({c});
                continue;
            }
            auto [it, added] = index.try_emplace({c->ray_set, c->threads}, out.size());
            if (added) out.emplace_back();
            out[it->second].push_back(c);
        }
        return out;
    }

private:
    // Measures results[i] for every i in `which` together in process `process`: their
    // measurements (pooled into the earlier processes' after the first) and their share of
    // the wall time. A later process times the combinations of the group still ok, a subset
    // of those an earlier one timed together, so its `timed_with` is the ids timed
    // alongside in every process.
    void measure_into(std::vector<CombinationResult>& results, const std::vector<size_t>& which,
                      const LoadedModel& model, int process) {
        if (which.empty()) return;
        std::vector<const Combination*> group;
        for (size_t i : which) group.push_back(&results[i].combination);
        const auto t0 = Clock::now();
        std::vector<Measurement> ms = measure_group(group, model, process);
        const double share = seconds_since(t0) / double(which.size());
        for (size_t k = 0; k < which.size(); ++k) {
            CombinationResult& r = results[which[k]];
            if (process == 1) {
                r.measurement = std::move(ms[k]);
                r.measuring_s = share;
                continue;
            }
            pool_process(r.measurement, ms[k], process);
            r.measurement.columns["timed_with"] = ms[k].columns["timed_with"];
            *r.measuring_s += share;
        }
    }

    // `group` in process `process`: one combination alone (measure_combination); several in
    // one child, interleaved (measure_jobs), each with the others' ids in `timed_with`.
    std::vector<Measurement> measure_group(const std::vector<const Combination*>& group, const LoadedModel& model,
                                           int process) {
        if (group.size() == 1) return {measure_combination(*group[0], model, process)};
        std::vector<MeasureJob> jobs;
        for (const Combination* c : group)
            jobs.push_back(MeasureJob{c->name, *find_accelerator(c->accel), c->params, render_of(plan_.config, *c),
                                      settings_of(*c, process), c->ray_set});
        first_measurement_ = false;
        auto work = [&](const StageFn& stage) { return measure_jobs(jobs, model, stage); };
        std::vector<Measurement> ms;
        if (options_.in_process) {
            ms = work(StageFn{});
        } else {
            // The child's deadline is every combination's own limit together.
            IsolatedMeasurements got = run_isolated_all(work, jobs.size(), plan_.config.timeout_s);
            if (got.process_failed) return after_failed_child(group, model, process, got.measurements[0]);
            ms = std::move(got.measurements);
        }
        for (size_t i = 0; i < group.size(); ++i) {
            std::vector<std::string> others;
            for (const Combination* c : group)
                if (c != group[i]) others.push_back(c->id);
            std::sort(others.begin(), others.end());
            ms[i].columns["timed_with"] = join_names(others, ";");
        }
        return ms;
    }

    // A group's child gave no result (it crashed or passed its deadline): the combination
    // whose stage it was in (the stage names it) gets the failure and the others are
    // measured again without it, so that one broken structure does not cost the others
    // their rows. When no stage names one (the child died before any), all get the failure.
    std::vector<Measurement> after_failed_child(const std::vector<const Combination*>& group, const LoadedModel& model,
                                                int process, const Measurement& failure) {
        auto culprit = std::find_if(group.begin(), group.end(),
                                    [&](const Combination* c) { return failure.stage.rfind(c->name + ": ", 0) == 0; });
        if (culprit == group.end()) return std::vector<Measurement>(group.size(), failure);
        std::vector<const Combination*> rest = group;
        rest.erase(rest.begin() + (culprit - group.begin()));
        std::vector<Measurement> out = measure_group(rest, model, process);
        out.insert(out.begin() + (culprit - group.begin()), failure);
        return out;
    }

    // What measuring combination c gets in process `process` (> 1: a later process, timing
    // only).
    MeasureSettings settings_of(const Combination& c, int process) const {
        MeasureSettings ms;
        ms.repetitions = repetitions_of(plan_.config, c);
        ms.warmup = warmup_of(plan_.config, c);
        ms.show_repetitions = options_.show_repetitions;
        ms.show_context = first_measurement_;
        ms.timing_only = process > 1;
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
        return ms;
    }

    // Timed (or judged, for a robustness case) in a child process that the time limit can
    // stop, unless --in-process.
    Measurement measure_combination(const Combination& c, const LoadedModel& model, int process) {
        const AcceleratorInfo* info = find_accelerator(c.accel);
        const MeasureSettings ms = settings_of(c, process);
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
        ModelOnDemand model(plan.config.models[mi], plan, mine, reference_wanted, options.in_process);
        // With several processes, the model's combinations are measured in turn, then all
        // again (interleaved, so that a drift in time shows as a gap between processes), and
        // each is reported once its last process is done. With `interleave`, the unit
        // measured in turn is a group (Runner::groups), its combinations in one child.
        int processes = 1;
        for (const Combination* c : mine) processes = std::max(processes, runner.processes(*c));
        std::vector<std::vector<CombinationResult>> pending;
        // False when an output cannot be written, which ends the run.
        auto report = [&](const CombinationResult& result) {
            not_loaded |= !result.written();
            errors |= result.written() && result.measurement.status == "error";
            try {
                for (RunSink* s : sinks) s->report(result);
            } catch (const std::exception& e) {
                std::fprintf(stderr, "accelbench run: %s\n", e.what());
                return false;
            }
            return true;
        };
        for (const std::vector<const Combination*>& group : runner.groups(mine, plan.config.models[mi])) {
            for (const Combination* c : group)
                for (RunSink* s : sinks) s->starting(*c);
            std::vector<CombinationResult> results = runner.run_group(group, model);
            if (processes > 1) pending.push_back(std::move(results));
            else
                for (const CombinationResult& r : results)
                    if (!report(r)) return 2;
        }
        for (int p = 2; p <= processes; ++p)
            for (std::vector<CombinationResult>& group : pending) runner.measure_again(group, model, p);
        for (const std::vector<CombinationResult>& group : pending)
            for (const CombinationResult& r : group)
                if (!report(r)) return 2;
    }
    for (RunSink* s : sinks) s->finalize();
    return not_loaded ? 2 : errors ? 1 : 0;
}

}  // namespace accelbench
