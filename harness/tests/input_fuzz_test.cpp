// Seeded random-mutation fuzzing of the two readers of user input: the mesh readers
// (every format, plain and gzip: one member, two, or one with bytes after it) and the
// config loader. Valid files are mutated (bytes
// flipped, inserted, deleted, duplicated, cut; words replaced by hostile numbers; line
// endings changed) for a bounded time, and every result must be one of two things: a
// refusal of the documented kind (std::runtime_error "cannot load mesh 'PATH': ...",
// ConfigError), or a load that is consistent — no NaN or out-of-limit vertex, every index
// in range, counts that agree. Anything else (another exception type, a crash, undefined
// behaviour under `make test-sanitize`) fails the test with the input that caused it.
//
// ACCELBENCH_FUZZ_SECONDS (default 1.5 per target) and ACCELBENCH_FUZZ_SEED (default
// fixed, so `make test` is reproducible) change the budget and the seed.
#include <gtest/gtest.h>
#include <zlib.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "accelbench/scene/mesh_io.h"
#include "config/config.h"
#include "harness_test_util.h"

namespace accelbench {
namespace {

namespace fs = std::filesystem;
using testing_util::registry;
using testing_util::write_file;

// Each fuzz test runs at least a fixed number of inputs (the same ones for a seed, whatever
// the machine's load: a time budget alone ran 38 config inputs in a sanitized build under a
// load of 9, and a "more than N inputs" check then failed on the load, not on the loader),
// then more until the time budget is spent.
constexpr uint64_t kMinMeshInputs = 100;
constexpr uint64_t kMinConfigInputs = 50;

double budget_seconds() {
    const char* s = std::getenv("ACCELBENCH_FUZZ_SECONDS");
    return s && *s ? std::atof(s) : 1.5;
}
uint64_t seed() {
    const char* s = std::getenv("ACCELBENCH_FUZZ_SEED");
    return s && *s ? std::strtoull(s, nullptr, 10) : 20261201;
}

// Shows an input in a failure message (printable, escaped, cut).
std::string escaped(const std::string& bytes) {
    std::string out;
    for (size_t i = 0; i < bytes.size() && i < 600; ++i) {
        const unsigned char c = static_cast<unsigned char>(bytes[i]);
        if (c == '\n') out += "\\n";
        else if (c >= 32 && c < 127) out += char(c);
        else {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", unsigned(c));
            out += hex;
        }
    }
    return out + (bytes.size() > 600 ? "..." : "");
}

class Mutator {
public:
    explicit Mutator(uint64_t seed) : rng_(seed) {}

    std::string mutate(std::string s) {
        const int rounds = 1 + int(pick(4));
        for (int r = 0; r < rounds; ++r) {
            const size_t n = s.size();
            switch (pick(9)) {
                case 0:  // flip a bit
                    if (n) s[pick(n)] ^= char(1u << pick(8));
                    break;
                case 1:  // insert an interesting byte
                    s.insert(s.begin() + std::ptrdiff_t(pick(n + 1)), interesting_byte());
                    break;
                case 2:  // delete a range
                    if (n) {
                        const size_t at = pick(n);
                        s.erase(at, 1 + pick(std::min<size_t>(16, n - at)));
                    }
                    break;
                case 3:  // duplicate a range
                    if (n) {
                        const size_t at = pick(n), len = 1 + pick(std::min<size_t>(64, n - at));
                        s.insert(pick(n + 1), s.substr(at, len));
                    }
                    break;
                case 4:  // cut the end
                    if (n) s.resize(pick(n));
                    break;
                case 5:  // replace a word (a run of non-blanks) by a hostile number
                    replace_word(s, hostile_word());
                    break;
                case 6:  // change a line ending
                    if (const size_t at = s.find('\n', pick(n + 1)); at != std::string::npos)
                        s.replace(at, 1, pick(2) ? "\r" : "\r\n");
                    break;
                case 7:  // overwrite 4 bytes with a hostile binary value (counts, floats)
                    if (n >= 4) {
                        const uint32_t values[] = {0xffffffffu,
                                                   0x7fc00000u /* NaN */,
                                                   0x7f800000u /* inf */,
                                                   0x80000000u,
                                                   0x0000000au,
                                                   0x5f800000u /* 1.8e19 */,
                                                   3,
                                                   0};
                        const uint32_t v = values[pick(std::size(values))];
                        std::memcpy(s.data() + pick(n - 3), &v, 4);
                    }
                    break;
                default:  // replace a byte by an interesting one
                    if (n) s[pick(n)] = interesting_byte();
                    break;
            }
        }
        return s;
    }

    size_t pick(size_t n) { return n ? size_t(rng_() % n) : 0; }

private:
    char interesting_byte() {
        static const char bytes[] = "\n\r \t#\\/-+.e0123456789nNaAiIfF:[]{},'\"\x00\xff";
        return bytes[pick(sizeof bytes - 1)];
    }
    std::string hostile_word() {
        static const char* const words[] = {
            "nan",        "-inf",       "inf",         "1e39",       "-1e400",
            "1e-50",      "1e19",       "0",           "-1",         "-0",
            "4294967295", "4294967296", "-2147483648", "2147483647", "99999999999999999999",
            "+",          "0x10",       "1.5.5",       "",           "#",
            "\\",         "3",          "4",           "255",        "256",
            "1000000000"};
        return words[pick(std::size(words))];
    }
    void replace_word(std::string& s, const std::string& word) {
        if (s.empty()) return;
        size_t at = pick(s.size());
        while (at > 0 && !std::isspace(static_cast<unsigned char>(s[at - 1]))) --at;
        size_t end = at;
        while (end < s.size() && !std::isspace(static_cast<unsigned char>(s[end]))) ++end;
        s.replace(at, end - at, word);
    }
    std::mt19937_64 rng_;
};

template <class T>
void put(std::string& bytes, T value) {
    bytes.append(reinterpret_cast<const char*>(&value), sizeof value);
}

struct Seed {
    std::string format, bytes;
};

std::vector<Seed> mesh_seeds() {
    std::vector<Seed> seeds = {
        {"obj",
         "# tiny\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1\nv 0.5 0.5 2.25\nvt 0 0\nvn 0 0 1\n"
         "f 1/1/1 2/1/1 3/1/1 4/1/1\nf -5 -4 \\\n -1\ng g\nusemtl m\n"},
        {"obj", "v 0 0 0\nv 1 0 0 \\\n\nv 1 1 0 # a comment ending in \\\nf 1 2 3 \\\n   # \\\nf 3 2 1\n"},
        {"ply",
         "ply\nformat ascii 1.0\ncomment c\nelement vertex 5\nproperty float x\nproperty float y\n"
         "property float z\nproperty uchar red\nelement face 2\nproperty list uchar int vertex_indices\n"
         "end_header\n0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n0.5 0.5 2.25 5\n4 0 1 2 3\n3 0 1 4\n"},
        {"off", "OFF\n# c\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 2.25\n4 0 1 2 3\n3 0 1 4 1 0 0\n"},
        {"off", "COFF 4 2 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1\n1 1 0 1 1 1\n0 1 0 1 1 1 1\n3 0 1 2\n3 0 2 3\n"},
        {"stl",
         "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\n"
         "endfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\nvertex 0 1 0.5\n"
         "endloop\nendfacet\nendsolid s\n"},
        {"stl",
         "solid one facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 1 1 0 endloop endfacet "
         "endsolid one solid two facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 1 0 vertex 0 1 0.5 endloop "
         "endfacet endsolid two"},
    };
    for (const char* format : {"binary_little_endian", "binary_big_endian"}) {
        std::string b = std::string("ply\nformat ") + format +
            " 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty double z\n"
            "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
        const bool big = std::string(format) == "binary_big_endian";
        const auto value = [&](auto v) {
            char raw[sizeof v];
            std::memcpy(raw, &v, sizeof v);
            if (big) std::reverse(raw, raw + sizeof v);
            b.append(raw, sizeof v);
        };
        const float xy[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
        for (int i = 0; i < 4; ++i) {
            value(xy[i][0]);
            value(xy[i][1]);
            value(double(i) * 0.5);
        }
        for (int f = 0; f < 2; ++f) {
            b += char(3);
            for (int32_t v : {0, 1 + f, 2 + f}) value(v);
        }
        seeds.push_back({"ply", b});
    }
    std::string stl(80, ' ');
    put(stl, uint32_t(2));
    const float tris[2][3][3] = {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, {{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}};
    for (auto& t : tris) {
        for (float n : {0.0f, 0.0f, 1.0f}) put(stl, n);
        for (auto& p : t)
            for (float c : p) put(stl, c);
        put(stl, uint16_t(0));
    }
    seeds.push_back({"stl", stl});
    return seeds;
}

// What a mesh that loaded must satisfy, whatever the input was.
void expect_consistent(const Scene& s, const MeshLoadInfo& info, const std::string& input) {
    ASSERT_GT(s.triangle_count(), 0u) << escaped(input);
    ASSERT_EQ(info.triangles, s.triangle_count()) << escaped(input);
    ASSERT_EQ(info.vertices, s.vertex_count()) << escaped(input);
    ASSERT_GE(info.triangles, info.file_faces) << escaped(input);
    ASSERT_LE(info.polygons, info.file_faces) << escaped(input);
    std::vector<bool> used(s.vertex_count());  // the scene's bounds are of the used vertices
    for (const auto& t : s.triangles)
        for (uint32_t i : t)
            if (i < used.size()) used[i] = true;
    for (const Vec3& v : s.vertices) {
        ASSERT_TRUE(within_coordinate_limit(v))
            << "vertex " << v.x << " " << v.y << " " << v.z << " from " << escaped(input);
        const Bounds3& b = s.bounds;
        const bool inside = b.lower.x <= v.x && v.x <= b.upper.x && b.lower.y <= v.y && v.y <= b.upper.y &&
            b.lower.z <= v.z && v.z <= b.upper.z;
        ASSERT_TRUE(inside || !used[size_t(&v - s.vertices.data())]) << escaped(input);
    }
    for (const auto& t : s.triangles)
        for (uint32_t i : t) ASSERT_LT(i, s.vertex_count()) << escaped(input);
    ASSERT_EQ(s.prim_bounds.size(), s.triangle_count());
}

TEST(InputFuzz, MeshReadersRefuseOrLoadConsistently) {
    const std::vector<Seed> seeds = mesh_seeds();
    for (const Seed& seed : seeds) {  // the seeds themselves load
        MeshLoadInfo info;
        expect_consistent(parse_mesh(seed.bytes, seed.format, "seed." + seed.format, &info), info, seed.bytes);
    }
    Mutator mutator(seed());
    TempDir dir("input_fuzz_test-");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(budget_seconds());
    uint64_t runs = 0, loaded = 0, gz_runs = 0;
    while (runs < kMinMeshInputs || std::chrono::steady_clock::now() < deadline) {
        const Seed& seed = seeds[runs % seeds.size()];
        const std::string input = mutator.mutate(seed.bytes);
        const std::string name = "fuzz." + seed.format;
        ++runs;
        try {
            MeshLoadInfo info;
            Scene s;
            if (runs % 64 == 0) {
                // Through a file, gzip-compressed, the compressed bytes mutated too: gunzip's
                // refusals and the file checks get their share. The input is one member,
                // two members split at a random byte (the same file), or one member and
                // bytes after it that are not a member (always refused).
                const auto pack = [&](const std::string& bytes) {
                    const std::string gz = (dir.path() / "p.gz").string();
                    gzFile out = gzopen(gz.c_str(), "wb");
                    gzwrite(out, bytes.data(), unsigned(bytes.size()));
                    gzclose(out);
                    return testing_util::read_file(gz);
                };
                const uint64_t form = (runs / 64) % 3;
                std::string packed;
                if (form == 1) {
                    const size_t cut = size_t(mutator.pick(input.size() + 1));
                    packed = pack(input.substr(0, cut)) + pack(input.substr(cut));
                } else {
                    packed = pack(input);
                }
                if (form == 2) {
                    std::string tail = mutator.mutate("trailing bytes");
                    if (tail.empty() || uint8_t(tail[0]) == 0x1f) tail.insert(0, 1, 'x');
                    const std::string path = write_file(dir.path(), name + ".gz", packed + tail);
                    ++gz_runs;
                    try {
                        load_mesh(path);
                        FAIL() << "bytes after the gzip data were not refused\ninput: " << escaped(input);
                    } catch (const std::runtime_error& e) {
                        ASSERT_NE(std::string(e.what()).find("bytes after the gzip data"), std::string::npos)
                            << e.what();
                    }
                    continue;
                }
                if (runs % 128 == 0) packed = mutator.mutate(packed);
                const std::string path = write_file(dir.path(), name + ".gz", packed);
                ++gz_runs;
                s = load_mesh(path, &info);
            } else {
                s = parse_mesh(input, seed.format, name, &info);
            }
            ++loaded;
            expect_consistent(s, info, input);
            if (::testing::Test::HasFatalFailure()) return;
        } catch (const std::runtime_error& e) {
            const std::string what = e.what();
            ASSERT_EQ(what.find("cannot load mesh '"), 0u) << what << "\ninput: " << escaped(input);
            ASSERT_GT(what.size(), 24u + name.size()) << what;  // a cause follows the name
        } catch (const std::exception& e) {
            FAIL() << "not a mesh load error: " << e.what() << "\ninput: " << escaped(input);
        }
    }
    std::printf("mesh fuzzing: %llu inputs (%llu through gzip files), %llu loaded, the rest refused\n",
                (unsigned long long)runs, (unsigned long long)gz_runs, (unsigned long long)loaded);
    EXPECT_GT(loaded, 0u);  // some mutations (a comment, a digit) keep the file valid
}

TEST(InputFuzz, ConfigLoaderRefusesOrLoadsConsistently) {
    std::vector<std::string> seeds = {
        "name: fuzz\nrepetitions: 2\ntimeout_s: 30\nrender: {width: 16, height: 12, light: true}\n"
        "models:\n  - stanford-bunny\n  - {procedural: soup, triangles: 100, seed: 1}\n"
        "  - {path: tri.obj, label: t, camera: {eye: [0, 0, 5], look_at: [0, 0, 0], up: [0, 1, 0], fov: 45}}\n"
        "accelerators:\n  - {name: bvh, params: {split: [median, sah], max_prims: {range: [1, 4]}}}\n"
        "  - {name: embree}\nskip:\n  - {accel: bvh, triangles_above: 5000, reason: slow}\n"};
    // The project's own configs (not the model registry) are seeds too.
    if (const char* source = std::getenv("ACCELBENCH_SOURCE_DIR"); source && *source)
        for (const auto& entry : fs::directory_iterator(fs::path(source) / "configs"))
            if (entry.path().extension() == ".yaml" && entry.path().filename() != "models.yaml")
                seeds.push_back(testing_util::read_file(entry.path().string()));
    TempDir dir("input_fuzz_test-");
    testing_util::write_triangle_case(dir.path());
    Mutator mutator(seed() + 1);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(budget_seconds());
    uint64_t runs = 0, loaded = 0;
    while (runs < kMinConfigInputs || std::chrono::steady_clock::now() < deadline) {
        const std::string input = mutator.mutate(seeds[runs % seeds.size()]);
        ++runs;
        const std::string path = write_file(dir.path(), "fuzz.yaml", input);
        try {
            const Config c = load_config(path, registry());
            ++loaded;
            ASSERT_FALSE(c.models.empty()) << escaped(input);
            ASSERT_FALSE(c.accelerators.empty()) << escaped(input);
            ASSERT_GE(c.repetitions, 1) << escaped(input);
            ASSERT_GE(c.warmup, 0) << escaped(input);
            ASSERT_TRUE(std::isfinite(c.timeout_s) && c.timeout_s > 0) << escaped(input);
            ASSERT_GT(c.render.width, 0) << escaped(input);
            ASSERT_GT(c.render.height, 0) << escaped(input);
            ASSERT_GE(c.render.spp, 1) << escaped(input);
            for (const ModelSpec& m : c.models) ASSERT_FALSE(m.name.empty()) << escaped(input);
        } catch (const ConfigError& e) {
            ASSERT_FALSE(std::string(e.what()).empty());
        } catch (const std::exception& e) {
            FAIL() << "not a ConfigError: " << e.what() << "\ninput: " << escaped(input);
        }
    }
    std::printf("config fuzzing: %llu inputs, %llu loaded, the rest refused\n", (unsigned long long)runs,
                (unsigned long long)loaded);
}

}  // namespace
}  // namespace accelbench
