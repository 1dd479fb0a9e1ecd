// What the mesh readers share (internal to scene/, not part of the interface): the
// error a reader throws, the words-and-numbers helpers, and the flat mesh every reader
// fills. One reader per format: mesh_obj.cpp, mesh_ply.cpp, mesh_off.cpp, mesh_stl.cpp,
// mesh_gltf.cpp;
// mesh_gzip.cpp inflates a .gz; mesh_io.cpp picks the reader.
#pragma once

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "accelbench/base/params.h"
#include "accelbench/scene/mesh_io.h"
#include "accelbench/scene/scene.h"

namespace accelbench::mesh_reading {

// A refusal at a place in the file ("line 12: face 3 has 2 corners"); parse_mesh puts
// the file's name in front.
struct MeshError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

[[noreturn]] inline void fail(const std::string& path, const std::string& reason) {
    throw std::runtime_error("cannot load mesh '" + path + "': " + reason);
}

inline std::string lowercase(std::string_view s) {
    std::string out(s);
    std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return out;
}

// A word of the file as a message shows it: quoted, cut at 40 characters, bytes that are
// not printable as \xNN (a corrupt file's words can be anything).
inline std::string shown(std::string_view word) {
    std::string out = "'";
    for (size_t i = 0; i < word.size() && i < 40; ++i) {
        const unsigned char c = static_cast<unsigned char>(word[i]);
        if (std::isprint(c)) {
            out += char(c);
        } else {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", unsigned(c));
            out += hex;
        }
    }
    return out + (word.size() > 40 ? "...'" : "'");
}

inline std::string number(uint64_t n) { return std::to_string(n); }

inline uint32_t byte_swapped(uint32_t x) {
    return (x >> 24) | ((x >> 8) & 0xff00u) | ((x << 8) & 0xff0000u) | (x << 24);
}
inline std::string line_at(uint64_t line) { return "line " + number(line) + ": "; }
inline std::string byte_at(uint64_t offset) { return "byte " + number(offset) + ": "; }

inline std::string point(Vec3 p) {
    char text[96];
    std::snprintf(text, sizeof text, "(%.9g, %.9g, %.9g)", double(p.x), double(p.y), double(p.z));
    return text;
}

// ---- words and numbers -------------------------------------------------------------

// Lines of a text, ending at LF, CR LF or a lone CR (all three occur in real files, and
// mixed within one); the last line needs no ending.
class Lines {
public:
    explicit Lines(std::string_view text) : text_(text) {}

    bool next(std::string_view& line) {
        if (pos_ >= text_.size()) return false;
        ++number_;
        size_t end = pos_;
        while (end < text_.size() && text_[end] != '\n' && text_[end] != '\r') ++end;
        if (end == text_.size()) {
            line = text_.substr(pos_);
            pos_ = text_.size();
            return true;
        }
        line = text_.substr(pos_, end - pos_);
        pos_ = end + (text_[end] == '\r' && end + 1 < text_.size() && text_[end + 1] == '\n' ? 2 : 1);
        return true;
    }
    uint64_t number() const { return number_; }  // of the line next() returned last, from 1
    size_t offset() const { return pos_; }       // of the byte after it and its ending

private:
    std::string_view text_;
    size_t pos_ = 0;
    uint64_t number_ = 0;
};

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

// The words of a line, separated by blanks.
inline void split_words(std::string_view line, std::vector<std::string_view>& words) {
    words.clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_blank(line[i])) ++i;
        const size_t start = i;
        while (i < line.size() && !is_blank(line[i])) ++i;
        if (i > start) words.push_back(line.substr(start, i - start));
    }
}

inline std::string_view strip_comment(std::string_view line) { return line.substr(0, line.find('#')); }

// A leading '+' is legal in all these formats' numbers; from_chars does not take it.
inline std::string_view without_plus(std::string_view s) {
    if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
    return s;
}

inline bool parse_int(std::string_view s, int64_t& value) {
    s = without_plus(s);
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    return ec == std::errc() && end == s.data() + s.size() && !s.empty();
}

enum class Real { ok, not_a_number, too_large };

// A decimal number rounded once to the nearest double ("nan" and "inf" are numbers here;
// the vertex check refuses them with their own message). Underflow rounds to zero;
// overflow is too_large.
inline Real parse_double(std::string_view s, double& value) {
    s = without_plus(s);
    if (s.empty()) return Real::not_a_number;
    const char* last = s.data() + s.size();
    const auto [end, ec] = std::from_chars(s.data(), last, value);
    if (end != last) return Real::not_a_number;
    if (ec == std::errc()) return Real::ok;
    // Out of range: an exponent like e-400 is a zero, e+400 too large.
    const size_t e = s.find_first_of("eE");
    if (e != std::string_view::npos && e + 1 < s.size() && s[e + 1] == '-') {
        value = s[0] == '-' ? -0.0 : 0.0;
        return Real::ok;
    }
    return Real::too_large;
}

// The same, rounded once to the nearest float (a denormal or zero on underflow).
inline Real parse_float(std::string_view s, float& value) {
    const std::string_view t = without_plus(s);
    const char* last = t.data() + t.size();
    const auto [end, ec] = std::from_chars(t.data(), last, value);
    if (!t.empty() && end == last && ec == std::errc()) return Real::ok;
    double wide = 0;
    const Real r = parse_double(s, wide);
    if (r != Real::ok) return r;
    if (!rounds_to_finite_float(wide)) return Real::too_large;
    value = round_to_float(wide);
    return Real::ok;
}

// Why a vertex cannot be loaded, or "" when it can: the same rule as Scene::finalize,
// applied to every vertex of a file (a non-finite vertex no face uses is a corrupt file
// all the same).
inline std::string vertex_problem(Vec3 p) {
    if (!is_finite(p)) return "a coordinate is not finite " + point(p);
    if (!within_coordinate_limit(p))
        return "a coordinate of magnitude 1.844e18 or more " + point(p) +
            " (the limit kMaxCoordinate, Embree's FLT_LARGE)";
    return "";
}

// Reads three coordinates from words; refuses what is not a float. `place()` names the
// place for a message (made only when one is needed: loading is on the benchmark's path).
template <class Place>
Vec3 coordinates(const std::string_view* words, const Place& place) {
    float xyz[3];
    for (int k = 0; k < 3; ++k) {
        const Real r = parse_float(words[k], xyz[k]);
        if (r == Real::not_a_number) throw MeshError(place() + "coordinate " + shown(words[k]) + " is not a number");
        if (r == Real::too_large)
            throw MeshError(place() + "coordinate " + shown(words[k]) + " is too large for a float");
    }
    return {xyz[0], xyz[1], xyz[2]};
}

// ---- what every reader produces --------------------------------------------------------

constexpr uint64_t kMaxIndex = std::numeric_limits<uint32_t>::max();  // a vertex index, a triangle count

struct FlatMesh {
    std::vector<Vec3> vertices;
    std::vector<std::array<uint32_t, 3>> triangles;
    uint64_t faces = 0;     // in the file
    uint64_t polygons = 0;  // of those, with more than three corners

    template <class Place>
    void add_vertex(Vec3 p, const Place& place) {
        if (vertices.size() >= kMaxIndex) throw MeshError("more than 4294967295 vertices (indices are 32-bit)");
        if (!within_coordinate_limit(p)) throw MeshError(place() + vertex_problem(p));
        vertices.push_back(p);
    }
    // Corners are vertex indices already checked; every face is kept as the file has it
    // (repeated corners, non-manifold neighbourhoods, unused vertices are the file's
    // business, and a ray tracer handles them). A polygon becomes a fan around corner 0.
    void add_face(const std::vector<uint32_t>& corners) {
        ++faces;
        if (corners.size() > 3) ++polygons;
        if (triangles.size() + corners.size() - 2 > kMaxIndex) throw MeshError("more than 4294967295 triangles");
        for (size_t k = 1; k + 1 < corners.size(); ++k) triangles.push_back({corners[0], corners[k], corners[k + 1]});
    }
};

inline std::string too_few_corners(uint64_t face, uint64_t corners) {
    return "face " + number(face) + " has " + number(corners) + " corner" + (corners == 1 ? "" : "s") +
        " (a face needs at least 3)";
}

// The readers, one per format, on a file's uncompressed bytes; they throw MeshError.
void read_obj(std::string_view text, FlatMesh& mesh);
void read_ply(std::string_view bytes, FlatMesh& mesh);
void read_off(std::string_view text, FlatMesh& mesh);
void read_stl(std::string_view bytes, FlatMesh& mesh);
// glTF (`binary`: a .glb container); external buffers are read from `folder` only. Returns
// the first perspective camera of the default scene, placed (mesh_gltf.cpp).
std::optional<Camera> read_gltf(std::string_view bytes, bool binary, const std::string& folder, FlatMesh& mesh);

// The decompressed bytes of the gzip file at `path`, every member in a row; refuses
// (through fail) a file that is not gzip, corrupt or truncated data, bytes after the last
// member, and more than `limit` bytes, as soon as the inflated size passes it.
std::string gunzip(const std::string& path, uint64_t limit = kMaxMeshFileBytes);

}  // namespace accelbench::mesh_reading
