#include "run/measure.h"
#include "accelbench/base/memory.h"
#include "plan/combinations.h"
#include "run/instructions.h"
#include "util/stats.h"
#include "util/text.h"

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <initializer_list>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace accelbench {

const std::vector<BuildStatField>& build_stat_fields() {
    static const std::vector<BuildStatField> fields = {
        {"nodes", &BuildStats::nodes, nullptr},          {"leaves", &BuildStats::leaves, nullptr},
        {"tree_depth", &BuildStats::max_depth, nullptr}, {"memory_bytes", &BuildStats::memory_bytes, nullptr},
        {"sah_cost", nullptr, &BuildStats::sah_cost},    {"avg_leaf_size", nullptr, &BuildStats::avg_leaf_size},
    };
    return fields;
}

namespace {

using Clock = std::chrono::steady_clock;

// CPU time of every thread of this process so far (CLOCK_PROCESS_CPUTIME_ID).
double process_cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

double seconds_between(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

// A time limit as the config wrote it (0.1, not 0.10000000000000001).
std::string limit_text(double s) { return number_text(s, 6); }

// ---- deterministic values: every run that produces them must agree ------------------

bool same_real(double a, double b) { return a == b || std::fabs(a - b) <= 1e-9 * std::max(std::fabs(a), std::fabs(b)); }

template <class T>
std::string opt_text(const std::optional<T>& v) {
    if (!v) return "missing";
    std::ostringstream s;
    s.precision(17);
    s << *v;
    return s.str();
}

// Empty when equal; otherwise which statistic differs and how. Counts must be equal,
// reals (SAH cost, averages) equal to a relative 1e-9.
std::string build_stats_difference(const BuildStats& a, const BuildStats& b) {
    auto differ = [](const std::optional<double>& x, const std::optional<double>& y) {
        return x.has_value() != y.has_value() || (x && !same_real(*x, *y));
    };
    auto describe = [](const std::string& what, const std::optional<double>& x, const std::optional<double>& y) {
        return what + " " + opt_text(x) + " vs " + opt_text(y);
    };
    for (const auto& f : build_stat_fields())
        if (differ(f.get(a), f.get(b))) return describe(f.name, f.get(a), f.get(b));
    std::set<std::string> keys;
    for (const auto& [k, v] : a.extra) keys.insert(k);
    for (const auto& [k, v] : b.extra) keys.insert(k);
    auto extra = [](const BuildStats& s, const std::string& k) {
        auto it = s.extra.find(k);
        return it == s.extra.end() ? std::nullopt : std::optional<double>(it->second);
    };
    for (const auto& k : keys)
        if (differ(extra(a, k), extra(b, k))) return describe(k, extra(a, k), extra(b, k));
    return "";
}

// "what x vs y" for the first of the named counts that differ; empty when all are equal.
std::string count_difference(std::initializer_list<std::tuple<std::string, uint64_t, uint64_t>> counts) {
    for (const auto& [what, x, y] : counts)
        if (x != y) return what + " " + std::to_string(x) + " vs " + std::to_string(y);
    return "";
}

// Ray and hit counts of two renders (TraceOutput) or two measurements (Measurement).
template <class Counted>
std::string ray_count_difference(const Counted& a, const Counted& b) {
    return count_difference({{"rays", a.rays, b.rays},
                             {"hits", a.hits, b.hits},
                             {"shadow_rays", a.shadow_rays, b.shadow_rays},
                             {"shadow_hits", a.shadow_hits, b.shadow_hits}});
}

std::string stats_difference(const std::string& prefix, const RayStats& a, const RayStats& b) {
    return count_difference({{prefix + "node_visits", a.node_visits, b.node_visits},
                             {prefix + "box_tests", a.box_tests, b.box_tests},
                             {prefix + "prim_tests", a.prim_tests, b.prim_tests}});
}

std::string counter_difference(const TraceOutput& a, const TraceOutput& b) {
    if (auto d = stats_difference("primary ", a.primary_stats, b.primary_stats); !d.empty()) return d;
    return stats_difference("shadow ", a.shadow_stats, b.shadow_stats);
}

// Every deterministic value of two measurements of one combination: build statistics, ray
// and hit counts, the traversal counters' totals; empty when all are equal.
std::string measurement_difference(const Measurement& a, const Measurement& b) {
    if (auto d = build_stats_difference(a.build, b.build); !d.empty()) return d;
    if (auto d = ray_count_difference(a, b); !d.empty()) return d;
    if (a.counts.has_value() != b.counts.has_value()) return "traversal counters present in one only";
    return a.counts ? stats_difference("", *a.counts, *b.counts) : "";
}

// Primary plus shadow totals; nullopt when the structure does not count its traversal
// (Embree), so that no zero is ever written for a count that was not made.
std::optional<RayStats> reported_counts(const AcceleratorInfo& info, const TraceOutput& out) {
    if (!info.counts_traversal) return std::nullopt;
    RayStats total = out.primary_stats;
    total += out.shadow_stats;
    return total;
}

struct Nondeterministic : std::runtime_error {
    using std::runtime_error::runtime_error;
};
struct StageTimeout : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// ---- the reporter: GB's console output, plus what the CSV needs ---------------------

// Passes runs on to GB's console reporter (only the aggregates unless every repetition
// is asked for) and, for --benchmark_out, to a JSON reporter writing into a string; keeps
// each counted repetition's time for our CSV. It is the display reporter: GB 1.7.1 only
// accepts a file reporter together with --benchmark_out, whose file the parent process
// owns.
class CaptureReporter : public benchmark::BenchmarkReporter {
public:
    // interleaved: each of Google Benchmark's runs is one repetition of one combination,
    // so the console shows none of them (they would be every repetition) and the group's
    // summary() stands for its aggregates.
    CaptureReporter(const MeasureSettings& s, bool interleaved)
        : settings_(s),
          interleaved_(interleaved),
          console_(benchmark::ConsoleReporter::OutputOptions(
              benchmark::ConsoleReporter::OO_Tabular |
              (isatty(STDOUT_FILENO) ? benchmark::ConsoleReporter::OO_Color : benchmark::ConsoleReporter::OO_None))) {
        if (!s.show_context) console_.SetErrorStream(&null_);
    }

    bool ReportContext(const Context& context) override { return console_.ReportContext(context); }

    void ReportRuns(const std::vector<Run>& runs) override {
        // GB reports the repetitions and then, in a second call, their aggregates (mean,
        // median, stddev, cv): by default the console shows the aggregates, and a single
        // repetition (not one of an interleaved group's) or a failed one as it is.
        std::vector<Run> shown;
        for (const auto& r : runs)
            if (settings_.show_repetitions || r.run_type == Run::RT_Aggregate ||
                (r.repetitions <= 1 && !interleaved_) || r.error_occurred)
                shown.push_back(r);
        if (!shown.empty()) console_.ReportRuns(shown);
        for (const auto& r : runs) {
            const std::string& f = r.run_name.function_name;
            const bool build = f.size() >= 6 && f.compare(f.size() - 6, 6, "/build") == 0;
            const std::string name = f.substr(0, f.size() - (build ? 6 : 7));  // "/build" or "/render"
            if (settings_.json) json_of(name).reporter.ReportRuns({r});
            if (r.run_type != Run::RT_Iteration || r.error_occurred) continue;
            (build ? build_s : render_s)[name].push_back(r.real_accumulated_time / double(r.iterations));
        }
    }

    void Finalize() override { console_.Finalize(); }

    // An interleaved group's console summary, one line per combination and stage timed:
    // the median of its repetitions and the interval of the median (util/stats.h).
    void summary(const std::vector<std::string>& names, std::ostream& out) const {
        if (!interleaved_ || settings_.show_repetitions) return;
        for (const std::string& name : names)
            for (const auto& [stage, samples] : {std::pair{"build", &build_s}, std::pair{"render", &render_s}}) {
                const auto it = samples->find(name);
                if (it == samples->end() || it->second.empty()) continue;
                const Summary t = summarize(it->second);
                char line[160];
                if (t.ci_lo && t.ci_hi)
                    std::snprintf(line, sizeof line, "median %.4g ms [%.4g, %.4g] of %zu repetitions, interleaved",
                                  1e3 * t.median, 1e3 * *t.ci_lo, 1e3 * *t.ci_hi, t.n);
                else  // one repetition: no interval, as the row's empty *_ci_lo and *_ci_hi
                    std::snprintf(line, sizeof line, "%.4g ms, one repetition, interleaved", 1e3 * t.median);
                out << name << "/" << stage << ": " << line << "\n";
            }
    }

    // The JSON run objects of one combination, comma-separated.
    std::string json(const std::string& name) const {
        auto it = json_.find(name);
        return it == json_.end() ? "" : it->second->text.str();
    }

    // Each combination's counted repetitions, by its name (the benchmarks' name before
    // "/build" and "/render"), in the order timed.
    std::map<std::string, std::vector<double>> build_s, render_s;

private:
    MeasureSettings settings_;
    bool interleaved_;
    benchmark::ConsoleReporter console_;
    // One JSON reporter per combination, so that each row's JSON holds its own runs only.
    struct JsonOut {
        std::ostringstream text;
        benchmark::JSONReporter reporter;
        JsonOut() {
            reporter.SetOutputStream(&text);
            reporter.SetErrorStream(&text);
        }
    };
    JsonOut& json_of(const std::string& name) {
        auto& out = json_[name];
        if (!out) out = std::make_unique<JsonOut>();
        return *out;
    }
    std::map<std::string, std::unique_ptr<JsonOut>> json_;
    std::ostream null_{nullptr};
};

// ---- the stages of measuring one combination ------------------------------------------

// One combination's measurement: what its stages share (the structure last built, the
// first build's statistics, the counting renders) and the stages themselves, each a
// function named for it. Google Benchmark calls build_benchmark() once per build
// repetition and then render_benchmark() once per render repetition; the stages run in
// this order:
//   1. warm-up builds (before the first counted build)
//   2. timed builds, one per repetition
//   3. the first counting render (also the first render warm-up), further render warm-ups
//   4. timed renders, one per repetition (under callgrind the first is also counted)
//   5. the second counting render, also the error trace: its counters must equal the
//      first one's; with reference answers it keeps every primary hit (and shades in an
//      image run), and after Google Benchmark returns its answers are compared with the
//      reference's (error_columns)
// The first failure (an exception, a nondeterministic value, the time limit) skips every
// later repetition and becomes the result's status.
class MeasuringStages {
public:
    MeasuringStages(const AcceleratorInfo& info, const ParamSet& params, const LoadedModel& model,
                    const RenderSettings& render, const MeasureSettings& settings, const StageFn& stage,
                    const GeneratedRaySet* ray_set, std::string stage_prefix)
        : info_(info),
          params_(params),
          model_(model),
          render_(render),
          settings_(settings),
          stage_(stage),
          stage_prefix_(std::move(stage_prefix)),
          ray_set_(ray_set) {
        timed_.settings = render;
        timed_.light = model.light;
        timed_.counts = CountMode::Off;
        timed_.albedo = model.albedo;
        counting_ = timed_;
        counting_.counts = CountMode::Totals;
        counting_.settings.shading = false;  // counts do not depend on shading
        // With reference answers, the second counting render is also the error trace: it
        // keeps every primary hit and, in an image run, shades (its counts must still equal
        // the first one's), so error measurement costs no render of its own.
        error_trace_ = counting_;
        if (model.reference || ray_set) {
            error_trace_.keep_hits = true;
            error_trace_.settings.shading = render.shading;
        }
    }

    void build_benchmark(benchmark::State& st) {
        guarded(st, [&] {
            const int rep = ++build_calls_;
            if (rep == 1) warm_up_builds();
            timed_build(st, rep);
        });
    }

    void render_benchmark(benchmark::State& st) {
        guarded(st, [&] {
            const int rep = ++render_calls_;
            if (!accel_) build_for_rendering();
            if (rep == 1) {
                first_counting_render();
                render_warm_ups();
            }
            const TraceOutput out = timed_render(st, rep);
            if (rep == settings_.repetitions && !settings_.timing_only) second_counting_render();
            render_counters(st, out);
        });
    }

    // After Google Benchmark returned: the failure, or the samples, the first counting
    // render's counts and the error columns of the second against the reference.
    Measurement result(const CaptureReporter& reporter, const std::string& name) {
        Measurement m = std::move(m_);
        m.json = reporter.json(name);
        const int reps = settings_.repetitions;
        static const std::vector<double> none;
        auto samples = [&](const std::map<std::string, std::vector<double>>& by_name) -> const std::vector<double>& {
            auto it = by_name.find(name);
            return it == by_name.end() ? none : it->second;
        };
        const std::vector<double>& build_s = samples(reporter.build_s);
        const std::vector<double>& render_s = samples(reporter.render_s);
        if (!failure_.empty()) {
            m.status = timed_out_ ? "timeout" : "error";
            m.message = failure_;
            if (failure_.rfind("nondeterministic", 0) == 0)
                std::fprintf(stderr, "accelbench run: %s: %s\n", name.c_str(), failure_.c_str());
            return m;
        }
        if (int(build_s.size()) != reps || int(render_s.size()) != reps || !first_count_ || !first_build_) {
            m.status = "error";
            m.message = "Google Benchmark reported " + std::to_string(build_s.size()) + " build and " +
                std::to_string(render_s.size()) + " render repetitions, expected " + std::to_string(reps) +
                " of each (a --benchmark_* flag may have filtered them)";
            return m;
        }
        try {
            if (auto errors = errors_against_reference()) m.columns = std::move(*errors);
        } catch (const std::exception& e) {
            m.status = "error";
            m.message = e.what();
            return m;
        }
        m.columns["peak_rss_bytes"] = std::to_string(peak_rss_bytes());
        m.build_s = build_s;
        m.render_s = render_s;
        m.render_cpu_s = render_cpu_s_;
        if (ray_set_) m.columns["ray_set_hash"] = hex16(ray_set_->hash);
        m.build = *first_build_;
        m.rays = first_count_->rays;
        m.hits = first_count_->hits;
        m.shadow_rays = first_count_->shadow_rays;
        m.shadow_hits = first_count_->shadow_hits;
        m.counts = reported_counts(info_, *first_count_);
        m.instructions = instructions_;
        return m;
    }

    // A failure outside the benchmarks (Google Benchmark itself threw).
    void failed(const std::exception& e) {
        if (failure_.empty()) failure_ = e.what();
    }

private:
    // ---- stage 1: warm-up builds
    void warm_up_builds() {
        for (int w = 0; w < settings_.warmup; ++w) {
            begin("build warm-up " + std::to_string(w + 1) + " of " + std::to_string(settings_.warmup));
            accel_ = build_checked("a warm-up build");
        }
    }

    // ---- stage 2: one timed build
    void timed_build(benchmark::State& st, int rep) {
        begin("build repetition " + std::to_string(rep) + " of " + std::to_string(settings_.repetitions));
        for (auto _ : st) {
            accel_.reset();  // at most one structure in memory at a time
            auto a = info_.create(params_);
            const auto t0 = Clock::now();
            a->build(model_.scene);
            const auto t1 = Clock::now();
            st.SetIterationTime(seconds_between(t0, t1));
            accel_ = std::move(a);
        }
        const BuildStats bs = accel_->build_stats();
        check_build(bs, "repetition " + std::to_string(rep));
        st.counters["triangles"] = double(model_.scene.triangle_count());
        for (const auto& f : build_stat_fields())
            if (auto v = f.get(bs)) st.counters[f.name] = *v;
    }

    // Only if Google Benchmark ran the render benchmark before the build benchmark.
    void build_for_rendering() {
        begin("build for rendering");
        accel_ = build_checked("the build for rendering");
    }

    // ---- stage 3: the first counting render, then the render warm-ups. The counting
    // render touches the same nodes and triangles as a timed one: it is the first warm-up;
    // further ones (warmup > 1) run the timed code path.
    void first_counting_render() {
        begin("counting render 1 of 2");
        first_count_ = trace(counting_);
        check_rays(*first_count_, "counting render 1");
    }

    void render_warm_ups() {
        for (int w = 1; w < settings_.warmup; ++w) {
            begin("render warm-up " + std::to_string(w + 1) + " of " + std::to_string(settings_.warmup));
            check_rays(trace(timed_), "a warm-up render");
        }
    }

    // ---- stage 4: one timed render. Under callgrind, the first counted repetition is also
    // the one whose instructions are counted: exactly one timed-mode render, nothing around it.
    TraceOutput timed_render(benchmark::State& st, int rep) {
        begin("render repetition " + std::to_string(rep) + " of " + std::to_string(settings_.repetitions));
        TraceOutput out;
        std::optional<CallgrindRegion> callgrind;
        if (rep == 1 && !settings_.callgrind_out.empty())
            callgrind.emplace(settings_.callgrind_out, settings_.callgrind_tag);
        for (auto _ : st) {
            if (callgrind) callgrind->start();
            const double cpu0 = process_cpu_seconds();
            const auto t0 = Clock::now();
            out = trace(timed_);
            const auto t1 = Clock::now();
            render_cpu_s_.push_back(process_cpu_seconds() - cpu0);
            if (callgrind) instructions_ = callgrind->stop();
            st.SetIterationTime(seconds_between(t0, t1));
        }
        check_rays(out, "render repetition " + std::to_string(rep));
        return out;
    }

    // ---- stage 5: the second counting render (the error trace), after the last timed render
    void second_counting_render() {
        begin("counting render 2 of 2");
        TraceOutput again = trace(error_trace_);
        check_rays(again, "counting render 2");
        if (auto d = counter_difference(*first_count_, again); !d.empty())
            throw Nondeterministic("nondeterministic traversal counters: " + d +
                                   " (counting render before vs after the timed repetitions)");
        second_count_ = std::move(again);
    }

    // Outside the timed part: the error trace's primary hits (and image, in an image run)
    // against the reference's answers; nullopt without reference answers.
    std::optional<std::map<std::string, std::string>> errors_against_reference() const {
        if (!model_.reference || !second_count_) return std::nullopt;
        if (ray_set_)
            return error_columns(ray_set_->query == RayQuery::Closest
                                     ? compare_hits(second_count_->primary_hits, ray_set_->reference_hits)
                                     : compare_occlusion(second_count_->occluded, ray_set_->reference_occluded),
                                 std::nullopt);
        std::optional<ImageErrors> image;
        if (second_count_->image && model_.reference->image)
            image = compare_images(*second_count_->image, *model_.reference->image, second_count_->primary_hits,
                                   model_.reference->hits, render_.spp);
        return error_columns(compare_hits(second_count_->primary_hits, model_.reference->hits), image);
    }

    // Google Benchmark's counters of a render repetition (its console table).
    void render_counters(benchmark::State& st, const TraceOutput& out) const {
        st.counters["rays"] = double(out.rays);
        st.counters["hits"] = double(out.hits);
        st.counters["shadow_rays"] = double(out.shadow_rays);
        st.counters["shadow_hits"] = double(out.shadow_hits);
        if (auto total = reported_counts(info_, *first_count_)) {
            st.counters["prim_tests"] = double(total->prim_tests);
            st.counters["node_visits"] = double(total->node_visits);
        }
        st.counters["Mrays/s"] =
            benchmark::Counter(double(out.rays + out.shadow_rays) * 1e-6, benchmark::Counter::kIsRate);
    }

    // ---- what every stage shares

    // A stage begins: reported to the parent process (named with the combination when
    // several share the process), checked against the time limit, which counts this
    // combination's own stages only: interleaved with others, their time is not its.
    void begin(const std::string& s) {
        m_.stage = s;
        if (stage_) stage_(stage_prefix_ + s);
        if (settings_.timeout_s > 0 && spent_s_ + seconds_between(entered_, Clock::now()) > settings_.timeout_s)
            throw StageTimeout("exceeded the time limit (timeout_s = " + limit_text(settings_.timeout_s) +
                               " s) before " + s);
    }

    // Runs a repetition's stages unless an earlier one failed; a failure skips this
    // repetition and every later one with the first failure's message.
    template <class F>
    void guarded(benchmark::State& st, F&& stages) {
        if (!failure_.empty()) return st.SkipWithError(failure_.c_str());
        entered_ = Clock::now();
        try {
            stages();
        } catch (const std::exception& e) {
            if (failure_.empty()) {
                failure_ = e.what();
                timed_out_ = dynamic_cast<const StageTimeout*>(&e) != nullptr;
            }
            st.SkipWithError(failure_.c_str());
        }
        spent_s_ += seconds_between(entered_, Clock::now());
    }

    std::unique_ptr<Accelerator> build_checked(const std::string& what) {
        auto a = info_.create(params_);
        a->build(model_.scene);
        check_build(a->build_stats(), what);
        return a;
    }

    void check_build(const BuildStats& bs, const std::string& what) {
        if (!first_build_) first_build_ = bs;
        else if (auto d = build_stats_difference(*first_build_, bs); !d.empty())
            throw Nondeterministic("nondeterministic build: " + d + " (first build vs " + what + ")");
    }

    void check_rays(const TraceOutput& out, const std::string& what) {
        if (!first_trace_) first_trace_ = out;
        else if (auto d = ray_count_difference(*first_trace_, out); !d.empty())
            throw Nondeterministic("nondeterministic render: " + d + " (first render vs " + what + ")");
    }

    TraceOutput trace(const TraceRequest& req) const {
        if (ray_set_) return trace_ray_set(*accel_, ray_set_->rays, ray_set_->query, req);
        return trace_model(*accel_, model_, req);
    }

    const AcceleratorInfo& info_;
    const ParamSet& params_;
    const LoadedModel& model_;
    const RenderSettings& render_;
    const MeasureSettings& settings_;
    const StageFn& stage_;
    const std::string stage_prefix_;  // "<name>: " in an interleaved group, else empty
    Clock::time_point entered_;       // when the repetition under way began
    double spent_s_ = 0;              // in this combination's repetitions before it
    TraceRequest timed_, counting_, error_trace_;

    Measurement m_;        // its stage: the last one begun
    std::string failure_;  // the first failure; later repetitions are skipped with it
    bool timed_out_ = false;
    int build_calls_ = 0, render_calls_ = 0;
    std::unique_ptr<Accelerator> accel_;  // the last one built; the render benchmark traces it
    std::optional<BuildStats> first_build_;
    std::optional<TraceOutput> first_trace_, first_count_, second_count_;
    std::optional<uint64_t> instructions_;
    const GeneratedRaySet* ray_set_;  // nullptr: the camera's (or ray file's) rays
    std::vector<double> render_cpu_s_;
};

}  // namespace

namespace {

using BenchmarkFn = std::function<void(benchmark::State&)>;

benchmark::internal::Benchmark* register_timed(const std::string& name, BenchmarkFn fn, int repetitions) {
    return benchmark::RegisterBenchmark(name.c_str(), std::move(fn))
        ->UseManualTime()
        ->Iterations(1)
        ->Repetitions(repetitions)
        ->Unit(benchmark::kMillisecond);
}

// Registers each combination's build and render benchmarks. One combination: two
// benchmarks of `repetitions` repetitions each, so that Google Benchmark shows their
// aggregates. Several: one single-repetition benchmark per round and combination, every
// build round before the render rounds; round k times the k-th repetition of every
// combination that has one, in the jobs' order in odd rounds and the reverse in even ones,
// so that neither side of a pair is always the one timed after the other. Google Benchmark
// runs registered benchmarks in the order registered (random interleaving off).
void register_benchmarks(const std::vector<MeasureJob>& jobs, std::vector<std::unique_ptr<MeasuringStages>>& stages) {
    auto build = [&](size_t j) {
        return BenchmarkFn([&, j](benchmark::State& st) { stages[j]->build_benchmark(st); });
    };
    auto render = [&](size_t j) {
        return BenchmarkFn([&, j](benchmark::State& st) { stages[j]->render_benchmark(st); });
    };
    if (jobs.size() == 1) {
        register_timed(jobs[0].name + "/build", build(0), jobs[0].settings.repetitions);
        register_timed(jobs[0].name + "/render", render(0), jobs[0].settings.repetitions);
        return;
    }
    int rounds = 0;
    for (const MeasureJob& j : jobs) rounds = std::max(rounds, j.settings.repetitions);
    for (const bool builds : {true, false})
        for (int k = 1; k <= rounds; ++k)
            for (size_t i = 0; i < jobs.size(); ++i) {
                const size_t j = k % 2 ? i : jobs.size() - 1 - i;
                if (jobs[j].settings.repetitions < k) continue;
                register_timed(jobs[j].name + (builds ? "/build" : "/render"), builds ? build(j) : render(j), 1);
            }
}

}  // namespace

std::vector<Measurement> measure_jobs(const std::vector<MeasureJob>& jobs, const LoadedModel& model,
                                      const StageFn& stage) {
    if (jobs.empty()) return {};
    reset_peak_rss();
    const bool shared = jobs.size() > 1;
    std::vector<std::unique_ptr<MeasuringStages>> stages;
    for (const MeasureJob& j : jobs)
        stages.push_back(std::make_unique<MeasuringStages>(j.info, j.params, model, j.render, j.settings, stage,
                                                           j.ray_set ? &model.ray_set(*j.ray_set) : nullptr,
                                                           shared ? j.name + ": " : ""));
    CaptureReporter reporter(jobs[0].settings, shared);
    benchmark::ClearRegisteredBenchmarks();
    register_benchmarks(jobs, stages);
    try {
        benchmark::RunSpecifiedBenchmarks(&reporter, std::string("."));
    } catch (const std::exception& e) {
        for (auto& s : stages) s->failed(e);
    }
    benchmark::ClearRegisteredBenchmarks();
    std::vector<std::string> names;
    for (const MeasureJob& j : jobs) names.push_back(j.name);
    reporter.summary(names, std::cout);
    std::cout.flush();
    std::vector<Measurement> out;
    for (size_t j = 0; j < jobs.size(); ++j) {
        out.push_back(stages[j]->result(reporter, jobs[j].name));
        // The process's high-water mark is of every structure of the group at once: no
        // combination's own, so none is written.
        if (shared) out.back().columns.erase("peak_rss_bytes");
    }
    return out;
}

Measurement measure(const std::string& name, const AcceleratorInfo& info, const ParamSet& params,
                    const LoadedModel& model, const RenderSettings& render_settings, const MeasureSettings& settings,
                    const StageFn& stage, std::optional<RaySetKind> ray_set) {
    return measure_jobs({MeasureJob{name, info, params, render_settings, settings, ray_set}}, model, stage)[0];
}

std::map<std::string, std::string> error_columns(const HitErrors& hits, const std::optional<ImageErrors>& image) {
    auto real = [](double v) { return number_text(v); };
    std::map<std::string, std::string> c = {{"false_misses", std::to_string(hits.false_misses)},
                                            {"false_hits", std::to_string(hits.false_hits)},
                                            {"prim_mismatches", std::to_string(hits.prim_mismatches)},
                                            {"nan_results", std::to_string(hits.nan_results)}};
    if (hits.t_err_ulp_p50) c["t_err_ulp_p50"] = real(*hits.t_err_ulp_p50);
    if (hits.t_err_ulp_max) c["t_err_ulp_max"] = real(*hits.t_err_ulp_max);
    if (image) {
        c["image_rmse"] = real(image->image_rmse);
        c["hole_pixels"] = std::to_string(image->hole_pixels);
    }
    return c;
}

void pool_process(Measurement& into, const Measurement& next, int process) {
    if (into.status != "ok") return;
    const std::string which = "process " + std::to_string(process);
    auto fail = [&](const std::string& status, const std::string& message) {
        into.status = status;
        into.message = message;
        into.stage = next.stage;
    };
    if (next.status != "ok") return fail(next.status, which + ": " + next.message);
    const std::string d = measurement_difference(into, next);
    if (!d.empty()) return fail("error", "nondeterministic between processes: " + d + " (process 1 vs " + which + ")");
    if (into.process.empty()) into.process.assign(into.render_s.size(), 1);
    into.build_s.insert(into.build_s.end(), next.build_s.begin(), next.build_s.end());
    into.render_s.insert(into.render_s.end(), next.render_s.begin(), next.render_s.end());
    into.render_cpu_s.insert(into.render_cpu_s.end(), next.render_cpu_s.begin(), next.render_cpu_s.end());
    into.process.insert(into.process.end(), next.render_s.size(), process);
    auto rss = [](const Measurement& m) {
        auto it = m.columns.find("peak_rss_bytes");
        return it == m.columns.end() ? uint64_t(0) : std::stoull(it->second);
    };
    if (rss(next) > rss(into)) into.columns["peak_rss_bytes"] = std::to_string(rss(next));
    if (!next.json.empty()) into.json += (into.json.empty() ? "" : ",") + next.json;
}

// ---- the wire form ----------------------------------------------------------------------

void put_measurement(WireWriter& w, const Measurement& m) {
    w.put_string(m.status);
    w.put_string(m.message);
    w.put_string(m.stage);
    w.put_vector(m.build_s);
    w.put_vector(m.render_s);
    w.put_vector(m.render_cpu_s);
    for (const auto& f : build_stat_fields()) {
        if (f.count) w.put_optional(m.build.*f.count);
        else w.put_optional(m.build.*f.real);
    }
    w.put_map(m.build.extra);
    for (uint64_t v : {m.rays, m.hits, m.shadow_rays, m.shadow_hits}) w.put(v);
    w.put_optional(m.counts);
    w.put_optional(m.instructions);
    w.put_map(m.columns);
    w.put_string(m.json);
}

Measurement take_measurement(WireReader& r) {
    Measurement m;
    m.status = r.take_string();
    m.message = r.take_string();
    m.stage = r.take_string();
    m.build_s = r.take_vector<double>();
    m.render_s = r.take_vector<double>();
    m.render_cpu_s = r.take_vector<double>();
    for (const auto& f : build_stat_fields()) {
        if (f.count) m.build.*f.count = r.take_optional<uint64_t>();
        else m.build.*f.real = r.take_optional<double>();
    }
    m.build.extra = r.take_map<double>();
    for (uint64_t* v : {&m.rays, &m.hits, &m.shadow_rays, &m.shadow_hits}) *v = r.take<uint64_t>();
    m.counts = r.take_optional<RayStats>();
    m.instructions = r.take_optional<uint64_t>();
    m.columns = r.take_map<std::string>();
    m.json = r.take_string();
    return m;
}

IsolatedMeasurements run_isolated_all(const std::function<std::vector<Measurement>(const StageFn&)>& work, size_t count,
                                      double timeout_s) {
    const double deadline_s = timeout_s * double(count);
    const ChildOutcome o = run_in_child(
        [&](const StageFn& stage) {
            std::vector<Measurement> ms;
            auto all_failed = [&](const std::string& message) {
                ms.assign(count, Measurement{});
                for (Measurement& m : ms) m.status = "error", m.message = message;
            };
            try {
                ms = work(stage);
            } catch (const std::exception& e) {
                all_failed(e.what());
            } catch (...) {
                all_failed("unknown exception");
            }
            WireWriter w;
            w.put(uint64_t(ms.size()));
            for (const Measurement& m : ms) put_measurement(w, m);
            return w.take();
        },
        deadline_s);
    IsolatedMeasurements out;
    if (o.result) {
        WireReader r(*o.result, "the measurements from their process");
        const uint64_t n = r.take<uint64_t>();
        if (n != count)
            throw std::logic_error("the measuring process sent " + std::to_string(n) + " measurements, " +
                                   std::to_string(count) + " expected");
        for (uint64_t i = 0; i < n; ++i) out.measurements.push_back(take_measurement(r));
        r.expect_end();
        return out;
    }
    Measurement m;
    m.stage = o.stage;
    if (o.timed_out) {
        m.status = "timeout";
        m.message = time_limit_message(timeout_s, o.stage, count);
    } else {
        m.status = "error";
        m.message = "the measurement process " + o.failure + " during " + o.stage;
    }
    out.measurements.assign(count, m);
    out.process_failed = true;
    return out;
}

Measurement run_isolated(const std::function<Measurement(const StageFn&)>& work, double timeout_s) {
    return run_isolated_all([&](const StageFn& stage) { return std::vector<Measurement>{work(stage)}; }, 1, timeout_s)
        .measurements[0];
}

}  // namespace accelbench
