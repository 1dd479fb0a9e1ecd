#include "run/measure.h"
#include "accelbench/base/memory.h"
#include "plan/combinations.h"
#include "run/instructions.h"
#include "util/text.h"

#include <benchmark/benchmark.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <iostream>
#include <set>
#include <sstream>
#include <stdexcept>

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

std::string ray_count_difference(const TraceOutput& a, const TraceOutput& b) {
    auto cmp = [](const char* what, uint64_t x, uint64_t y) {
        return x == y ? std::string() : std::string(what) + " " + std::to_string(x) + " vs " + std::to_string(y);
    };
    for (const std::string& d :
         {cmp("rays", a.rays, b.rays), cmp("hits", a.hits, b.hits), cmp("shadow_rays", a.shadow_rays, b.shadow_rays),
          cmp("shadow_hits", a.shadow_hits, b.shadow_hits)})
        if (!d.empty()) return d;
    return "";
}

std::string counter_difference(const TraceOutput& a, const TraceOutput& b) {
    auto cmp = [](const std::string& what, uint64_t x, uint64_t y) {
        return x == y ? std::string() : what + " " + std::to_string(x) + " vs " + std::to_string(y);
    };
    for (const std::string& d : {cmp("primary node_visits", a.primary_stats.node_visits, b.primary_stats.node_visits),
                                 cmp("primary box_tests", a.primary_stats.box_tests, b.primary_stats.box_tests),
                                 cmp("primary prim_tests", a.primary_stats.prim_tests, b.primary_stats.prim_tests),
                                 cmp("shadow node_visits", a.shadow_stats.node_visits, b.shadow_stats.node_visits),
                                 cmp("shadow box_tests", a.shadow_stats.box_tests, b.shadow_stats.box_tests),
                                 cmp("shadow prim_tests", a.shadow_stats.prim_tests, b.shadow_stats.prim_tests)})
        if (!d.empty()) return d;
    return "";
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
    explicit CaptureReporter(const MeasureSettings& s)
        : settings_(s),
          console_(benchmark::ConsoleReporter::OutputOptions(
              benchmark::ConsoleReporter::OO_Tabular |
              (isatty(STDOUT_FILENO) ? benchmark::ConsoleReporter::OO_Color : benchmark::ConsoleReporter::OO_None))) {
        json_.SetOutputStream(&json_text_);
        json_.SetErrorStream(&json_text_);
        if (!s.show_context) console_.SetErrorStream(&null_);
    }

    bool ReportContext(const Context& context) override { return console_.ReportContext(context); }

    void ReportRuns(const std::vector<Run>& runs) override {
        // GB reports the repetitions and then, in a second call, their aggregates (mean,
        // median, stddev, cv): by default the console shows the aggregates, and a single
        // repetition or a failed one as it is.
        std::vector<Run> shown;
        for (const auto& r : runs)
            if (settings_.show_repetitions || r.run_type == Run::RT_Aggregate || r.repetitions <= 1 || r.error_occurred)
                shown.push_back(r);
        if (!shown.empty()) console_.ReportRuns(shown);
        if (settings_.json) json_.ReportRuns(runs);
        for (const auto& r : runs) {
            if (r.run_type != Run::RT_Iteration || r.error_occurred) continue;
            const bool build = r.run_name.function_name.size() >= 6 &&
                r.run_name.function_name.compare(r.run_name.function_name.size() - 6, 6, "/build") == 0;
            (build ? build_s : render_s).push_back(r.real_accumulated_time / double(r.iterations));
        }
    }

    void Finalize() override { console_.Finalize(); }

    std::string json() const { return json_text_.str(); }

    std::vector<double> build_s, render_s;

private:
    MeasureSettings settings_;
    benchmark::ConsoleReporter console_;
    benchmark::JSONReporter json_;
    std::ostringstream json_text_;
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
                    const GeneratedRaySet* ray_set)
        : info_(info),
          params_(params),
          model_(model),
          render_(render),
          settings_(settings),
          stage_(stage),
          start_(Clock::now()),
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
            if (rep == settings_.repetitions) second_counting_render();
            render_counters(st, out);
        });
    }

    // After Google Benchmark returned: the failure, or the samples, the first counting
    // render's counts and the error columns of the second against the reference.
    Measurement result(const CaptureReporter& reporter, const std::string& name) {
        Measurement m = std::move(m_);
        m.json = reporter.json();
        const int reps = settings_.repetitions;
        if (!failure_.empty()) {
            m.status = timed_out_ ? "timeout" : "error";
            m.message = failure_;
            if (failure_.rfind("nondeterministic", 0) == 0)
                std::fprintf(stderr, "accelbench run: %s: %s\n", name.c_str(), failure_.c_str());
            return m;
        }
        if (int(reporter.build_s.size()) != reps || int(reporter.render_s.size()) != reps || !first_count_ ||
            !first_build_) {
            m.status = "error";
            m.message = "Google Benchmark reported " + std::to_string(reporter.build_s.size()) + " build and " +
                std::to_string(reporter.render_s.size()) + " render repetitions, expected " + std::to_string(reps) +
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
        m.build_s = reporter.build_s;
        m.render_s = reporter.render_s;
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

    // A stage begins: reported to the parent process, checked against the time limit.
    void begin(const std::string& s) {
        m_.stage = s;
        if (stage_) stage_(s);
        if (settings_.timeout_s > 0 && seconds_between(start_, Clock::now()) > settings_.timeout_s)
            throw StageTimeout("exceeded the time limit (timeout_s = " + limit_text(settings_.timeout_s) +
                               " s) before " + s);
    }

    // Runs a repetition's stages unless an earlier one failed; a failure skips this
    // repetition and every later one with the first failure's message.
    template <class F>
    void guarded(benchmark::State& st, F&& stages) {
        if (!failure_.empty()) return st.SkipWithError(failure_.c_str());
        try {
            stages();
        } catch (const std::exception& e) {
            if (failure_.empty()) {
                failure_ = e.what();
                timed_out_ = dynamic_cast<const StageTimeout*>(&e) != nullptr;
            }
            st.SkipWithError(failure_.c_str());
        }
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
    const Clock::time_point start_;
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

Measurement measure(const std::string& name, const AcceleratorInfo& info, const ParamSet& params,
                    const LoadedModel& model, const RenderSettings& render_settings, const MeasureSettings& settings,
                    const StageFn& stage, std::optional<RaySetKind> ray_set) {
    reset_peak_rss();
    MeasuringStages stages(info, params, model, render_settings, settings, stage,
                           ray_set ? &model.ray_set(*ray_set) : nullptr);
    CaptureReporter reporter(settings);
    benchmark::ClearRegisteredBenchmarks();
    for (auto [suffix, fn] : {std::pair<const char*, std::function<void(benchmark::State&)>>{
                                  "/build", [&](benchmark::State& st) { stages.build_benchmark(st); }},
                              {"/render", [&](benchmark::State& st) { stages.render_benchmark(st); }}})
        benchmark::RegisterBenchmark((name + suffix).c_str(), fn)
            ->UseManualTime()
            ->Iterations(1)
            ->Repetitions(settings.repetitions)
            ->Unit(benchmark::kMillisecond);
    try {
        benchmark::RunSpecifiedBenchmarks(&reporter, std::string("."));
    } catch (const std::exception& e) {
        stages.failed(e);
    }
    benchmark::ClearRegisteredBenchmarks();
    std::cout.flush();
    return stages.result(reporter, name);
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

// ---- the text form --------------------------------------------------------------------

namespace {

std::string escape(const std::string& s) {
    std::string out;
    for (char ch : s) {
        if (ch == '\\') out += "\\\\";
        else if (ch == '\n') out += "\\n";
        else out += ch;
    }
    return out;
}

std::string unescape(const std::string& s) {
    std::string out;
    for (size_t i = 0; i < s.size(); ++i) {
        if (s[i] == '\\' && i + 1 < s.size()) {
            out += s[i + 1] == 'n' ? '\n' : s[i + 1];
            ++i;
        } else {
            out += s[i];
        }
    }
    return out;
}

// Exact: 17 significant digits give back the same double.
std::string real_text(double v) { return number_text(v, 17); }

std::string list_text(const std::vector<double>& v) {
    std::string s;
    for (double x : v) append_item(s, " ", real_text(x));
    return s;
}

std::vector<double> parse_list(const std::string& s) {
    std::vector<double> v;
    std::istringstream in(s);
    for (std::string tok; in >> tok;) v.push_back(std::strtod(tok.c_str(), nullptr));
    return v;
}

}  // namespace

std::string serialize(const Measurement& m) {
    std::string s;
    auto put = [&](const std::string& k, const std::string& v) { s += k + "=" + escape(v) + "\n"; };
    put("status", m.status);
    put("message", m.message);
    put("stage", m.stage);
    put("build_s", list_text(m.build_s));
    put("render_s", list_text(m.render_s));
    put("render_cpu_s", list_text(m.render_cpu_s));
    for (const auto& f : build_stat_fields())
        if (auto v = f.get(m.build))
            put(std::string("build.") + f.name, f.count ? std::to_string(*(m.build.*f.count)) : real_text(*v));
    for (const auto& [k, v] : m.build.extra) put("extra." + k, real_text(v));
    put("rays", std::to_string(m.rays));
    put("hits", std::to_string(m.hits));
    put("shadow_rays", std::to_string(m.shadow_rays));
    put("shadow_hits", std::to_string(m.shadow_hits));
    if (m.counts) {
        put("node_visits", std::to_string(m.counts->node_visits));
        put("box_tests", std::to_string(m.counts->box_tests));
        put("prim_tests", std::to_string(m.counts->prim_tests));
    }
    if (m.instructions) put("instructions", std::to_string(*m.instructions));
    for (const auto& [k, v] : m.columns) put("column." + k, v);
    put("json", m.json);
    return s;
}

Measurement deserialize(const std::string& text) {
    Measurement m;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        const size_t eq = line.find('=');
        if (eq == std::string::npos) throw std::runtime_error("malformed measurement line '" + line + "'");
        const std::string k = line.substr(0, eq), v = unescape(line.substr(eq + 1));
        auto u = [&] { return uint64_t(std::strtoull(v.c_str(), nullptr, 10)); };
        auto d = [&] { return std::strtod(v.c_str(), nullptr); };
        auto counts = [&]() -> RayStats& {
            if (!m.counts) m.counts = RayStats{};
            return *m.counts;
        };
        if (k == "status") m.status = v;
        else if (k == "message") m.message = v;
        else if (k == "stage") m.stage = v;
        else if (k == "build_s") m.build_s = parse_list(v);
        else if (k == "render_s") m.render_s = parse_list(v);
        else if (k == "render_cpu_s") m.render_cpu_s = parse_list(v);
        else if (k.rfind("build.", 0) == 0) {
            const BuildStatField* f = nullptr;
            for (const auto& field : build_stat_fields())
                if (k.substr(6) == field.name) f = &field;
            if (!f) throw std::runtime_error("unknown build statistic '" + k + "'");
            if (f->count) m.build.*(f->count) = u();
            else m.build.*(f->real) = d();
        } else if (k.rfind("extra.", 0) == 0) m.build.extra[k.substr(6)] = d();
        else if (k == "rays") m.rays = u();
        else if (k == "hits") m.hits = u();
        else if (k == "shadow_rays") m.shadow_rays = u();
        else if (k == "shadow_hits") m.shadow_hits = u();
        else if (k == "node_visits") counts().node_visits = u();
        else if (k == "box_tests") counts().box_tests = u();
        else if (k == "prim_tests") counts().prim_tests = u();
        else if (k == "instructions") m.instructions = u();
        else if (k.rfind("column.", 0) == 0) m.columns[k.substr(7)] = v;
        else if (k == "json") m.json = v;
        else throw std::runtime_error("unknown measurement key '" + k + "'");
    }
    return m;
}

// ---- the child process ------------------------------------------------------------------

namespace {

void write_all(int fd, const std::string& data) {
    size_t done = 0;
    while (done < data.size()) {
        ssize_t n = ::write(fd, data.data() + done, data.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;  // the parent is gone; nothing to report to
        done += size_t(n);
    }
}

// Frames on the pipe: a tag ('S' stage begun, 'R' result), the payload length, a newline,
// the payload.
void send_frame(int fd, char tag, const std::string& payload) {
    write_all(fd, std::string(1, tag) + std::to_string(payload.size()) + "\n" + payload);
}

// Everything buffered for stdout and stderr, C++ streams and C stdio, written out: before a
// fork (or the child would write the parent's buffered text a second time), before a child
// exits, and before the parent stops itself.
void flush_all_output() {
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
}

// A child killed by a request to stop — SIGTERM (scancel, a Slurm time limit, kill),
// SIGINT (Ctrl-C), SIGHUP, SIGQUIT — was not failed by its combination: the whole run is
// being stopped, and the same signal is on its way to this process (Slurm and a terminal
// signal every process of the job). Found by make test-slurm: the child died
// first, this parent wrote `status=error, the measurement process died from signal 15
// (Terminated)` before its own SIGTERM arrived, and `--resume` then kept that row instead
// of measuring the combination again, so the merged grid differed from a single-process
// run. So the parent stops itself the same way, now, without a row for the combination;
// its earlier rows are on disk (each is flushed when written), and --resume measures the
// interrupted combination again (dropping its orphaned repetition rows). A crash of the
// structure (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) and the kernel's OOM kill (SIGKILL)
// stay error rows.
void stop_if_asked_to_stop(int signal_number) {
    if (signal_number != SIGTERM && signal_number != SIGINT && signal_number != SIGHUP && signal_number != SIGQUIT)
        return;
    flush_all_output();
    std::signal(signal_number, SIG_DFL);
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, signal_number);
    sigprocmask(SIG_UNBLOCK, &set, nullptr);
    std::raise(signal_number);
    _exit(128 + signal_number);  // not reached; the shell's code for a death by that signal
}

}  // namespace

ChildOutcome run_in_child(const std::function<std::string(const StageFn&)>& work, double timeout_s,
                          const std::string& first_stage) {
    int fds[2];
    if (pipe(fds) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
    flush_all_output();
    const pid_t pid = fork();
    if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    if (pid == 0) {
        ::close(fds[0]);
        prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive a killed parent
        const std::string result = work([&](const std::string& s) { send_frame(fds[1], 'S', s); });
        send_frame(fds[1], 'R', result);
        flush_all_output();
        _exit(0);
    }
    ::close(fds[1]);

    const auto deadline =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
    std::string buffer;
    ChildOutcome o;
    o.stage = first_stage;
    for (;;) {
        const double left = seconds_between(Clock::now(), deadline);
        // Past the deadline, what the child already sent is still read (without waiting), so
        // a stage it reported before the limit names the stage it was stopped in — under load
        // the parent can wake after the deadline with the child's last frames unread.
        pollfd p{fds[0], POLLIN, 0};
        const int r = poll(&p, 1, left <= 0 ? 0 : int(std::min(left * 1000.0 + 1.0, 3.6e6)));
        if (r < 0 && errno == EINTR) continue;
        if (r == 0 && left <= 0) {
            o.timed_out = true;
            break;
        }
        if (r == 0) continue;  // the loop head decides whether time is up
        char chunk[65536];
        const ssize_t n = ::read(fds[0], chunk, sizeof chunk);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;  // the child closed the pipe: finished or died
        buffer.append(chunk, size_t(n));
        for (;;) {
            const size_t nl = buffer.find('\n');
            if (nl == std::string::npos) break;
            const size_t len = std::strtoull(buffer.c_str() + 1, nullptr, 10);
            if (buffer.size() < nl + 1 + len) {
                buffer.reserve(nl + 1 + len);  // a prepared model can be hundreds of MB: grow once
                break;
            }
            if (buffer[0] == 'R' && buffer.size() == nl + 1 + len) {
                // The last frame, alone in the buffer (as a result is): taken without a copy.
                buffer.erase(0, nl + 1);
                o.result = std::move(buffer);
                buffer.clear();
                break;
            }
            if (buffer[0] == 'S') o.stage = buffer.substr(nl + 1, len);
            else if (buffer[0] == 'R') o.result = buffer.substr(nl + 1, len);
            buffer.erase(0, nl + 1 + len);
        }
    }
    if (o.timed_out) kill(pid, SIGKILL);
    ::close(fds[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    if (!o.timed_out && WIFSIGNALED(status)) stop_if_asked_to_stop(WTERMSIG(status));
    if (o.timed_out) o.result.reset();
    if (!o.result && !o.timed_out) {
        o.failure = WIFSIGNALED(status)
            ? "died from signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")"
            : "exited with status " + std::to_string(WEXITSTATUS(status)) + " without a result";
    }
    return o;
}

std::string time_limit_message(double timeout_s, const std::string& stage) {
    return "exceeded the time limit (timeout_s = " + limit_text(timeout_s) + " s) during " + stage;
}

Measurement run_isolated(const std::function<Measurement(const StageFn&)>& work, double timeout_s) {
    const ChildOutcome o = run_in_child(
        [&](const StageFn& stage) {
            Measurement m;
            try {
                m = work(stage);
            } catch (const std::exception& e) {
                m.status = "error";
                m.message = e.what();
            } catch (...) {
                m.status = "error";
                m.message = "unknown exception";
            }
            return serialize(m);
        },
        timeout_s);
    if (o.result) return deserialize(*o.result);
    Measurement m;
    m.stage = o.stage;
    if (o.timed_out) {
        m.status = "timeout";
        m.message = time_limit_message(timeout_s, o.stage);
    } else {
        m.status = "error";
        m.message = "the measurement process " + o.failure + " during " + o.stage;
    }
    return m;
}

}  // namespace accelbench
