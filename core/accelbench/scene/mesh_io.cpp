#include "accelbench/scene/mesh_io.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <unordered_map>
#include <vector>

namespace accelbench {
namespace {

namespace fs = std::filesystem;

// A refusal at a place in the file ("line 12: face 3 has 2 corners"); parse_mesh puts
// the file's name in front.
struct MeshError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
    throw std::runtime_error("cannot load mesh '" + path + "': " + reason);
}

std::string lowercase(std::string_view s) {
    std::string out(s);
    std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return out;
}

// A word of the file as a message shows it: quoted, cut at 40 characters, bytes that are
// not printable as \xNN (a corrupt file's words can be anything).
std::string shown(std::string_view word) {
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

std::string number(uint64_t n) { return std::to_string(n); }

uint32_t byte_swapped(uint32_t x) { return (x >> 24) | ((x >> 8) & 0xff00u) | ((x << 8) & 0xff0000u) | (x << 24); }
std::string line_at(uint64_t line) { return "line " + number(line) + ": "; }
std::string byte_at(uint64_t offset) { return "byte " + number(offset) + ": "; }

std::string point(Vec3 p) {
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

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

// The words of a line, separated by blanks.
void split_words(std::string_view line, std::vector<std::string_view>& words) {
    words.clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_blank(line[i])) ++i;
        const size_t start = i;
        while (i < line.size() && !is_blank(line[i])) ++i;
        if (i > start) words.push_back(line.substr(start, i - start));
    }
}

std::string_view strip_comment(std::string_view line) { return line.substr(0, line.find('#')); }

// A leading '+' is legal in all these formats' numbers; from_chars does not take it.
std::string_view without_plus(std::string_view s) {
    if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
    return s;
}

bool parse_int(std::string_view s, int64_t& value) {
    s = without_plus(s);
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    return ec == std::errc() && end == s.data() + s.size() && !s.empty();
}

enum class Real { ok, not_a_number, too_large };

// A decimal number rounded once to the nearest double ("nan" and "inf" are numbers here;
// the vertex check refuses them with their own message). Underflow rounds to zero;
// overflow is too_large.
Real parse_double(std::string_view s, double& value) {
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
Real parse_float(std::string_view s, float& value) {
    const std::string_view t = without_plus(s);
    const char* last = t.data() + t.size();
    const auto [end, ec] = std::from_chars(t.data(), last, value);
    if (!t.empty() && end == last && ec == std::errc()) return Real::ok;
    double wide = 0;
    const Real r = parse_double(s, wide);
    if (r != Real::ok) return r;
    if (std::fabs(wide) > double(std::numeric_limits<float>::max())) return Real::too_large;
    value = float(wide);
    return Real::ok;
}

// Why a vertex cannot be loaded, or "" when it can: the same rule as Scene::finalize,
// applied to every vertex of a file (a non-finite vertex no face uses is a corrupt file
// all the same).
std::string vertex_problem(Vec3 p) {
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

std::string too_few_corners(uint64_t face, uint64_t corners) {
    return "face " + number(face) + " has " + number(corners) + " corner" + (corners == 1 ? "" : "s") +
        " (a face needs at least 3)";
}

// ---- OBJ (Wavefront, "Object Files (.obj)", Appendix B1 of the Advanced Visualizer
// manual) -------------------------------------------------------------------------------
//
// A statement per line; a line ending in '\' continues on the next; '#' starts a comment
// to the end of the line. "v x y z [w]" (colour extensions: up to 7 numbers); "f" with 3
// or more corners v, v/vt, v/vt/vn or v//vn, indices counting from 1, negative ones
// relative to the last vertex defined so far. Other statements of the specification
// (vt, vn, groups, materials, smoothing, curves and surfaces, lines, points) are read
// over: they carry no triangles. An unknown statement is refused.
bool obj_statement_without_triangles(std::string_view keyword) {
    static const std::vector<std::string_view> known = {
        "vp",         "cstype",    "deg",   "bmat",  "step",     "p",        "l",    "curv",   "curv2",
        "surf",       "parm",      "trim",  "hole",  "scrv",     "sp",       "end",  "con",    "g",
        "s",          "mg",        "o",     "bevel", "c_interp", "d_interp", "lod",  "usemtl", "mtllib",
        "shadow_obj", "trace_obj", "ctech", "stech", "maplib",   "usemap",   "call", "csh"};
    return std::find(known.begin(), known.end(), keyword) != known.end();
}

void read_obj(std::string_view text, FlatMesh& mesh) {
    Lines lines(text);
    std::string joined;
    std::vector<std::string_view> words, parts;
    std::vector<uint32_t> corners;
    uint64_t texcoords = 0, normals = 0;
    // Positive indices may refer to vertices defined later; the largest is checked at the
    // end. Texture coordinate and normal indices carry no geometry: they are checked as
    // indices (an integer, not 0), not against the counts.
    struct Reference {
        uint64_t index = 0, line = 0, face = 0;
    } max_vertex, unchecked;
    std::string_view physical;
    while (lines.next(physical)) {
        const uint64_t line_no = lines.number();
        std::string_view line = physical;
        const auto continued = [](std::string_view l) {
            const size_t last = l.find_last_not_of(" \t\v\f");
            return last != std::string_view::npos && l[last] == '\\' ? last : std::string_view::npos;
        };
        if (size_t cut = continued(line); cut != std::string_view::npos) {
            joined.assign(line.substr(0, cut));
            for (;;) {
                if (!lines.next(physical))
                    throw MeshError(line_at(line_no) + "a line continuation ('\\') at the end of the file");
                joined += ' ';
                cut = continued(physical);
                if (cut == std::string_view::npos) {
                    joined += physical;
                    break;
                }
                joined += physical.substr(0, cut);
            }
            line = joined;
        }
        split_words(strip_comment(line), words);
        if (words.empty()) continue;
        const std::string_view keyword = words[0];
        const size_t n = words.size() - 1;
        if (keyword == "v") {
            const auto place = [&] { return line_at(line_no) + "vertex " + number(mesh.vertices.size() + 1) + ": "; };
            if (n < 3 || n > 7)
                throw MeshError(place() + "a 'v' statement has " + number(n) +
                                " numbers (x y z, optionally w or a colour: 3 to 7)");
            for (size_t k = 4; k <= n; ++k) {
                float ignored;
                if (parse_float(words[k], ignored) == Real::not_a_number)
                    throw MeshError(place() + shown(words[k]) + " is not a number");
            }
            mesh.add_vertex(coordinates(&words[1], place), place);
        } else if (keyword == "vt" || keyword == "vn") {
            const bool normal = keyword == "vn";
            if (normal ? n != 3 : (n < 1 || n > 3))
                throw MeshError(line_at(line_no) + "a '" + std::string(keyword) + "' statement has " + number(n) +
                                " numbers (" + (normal ? "3" : "1 to 3") + ")");
            for (size_t k = 1; k <= n; ++k) {
                float value;
                if (parse_float(words[k], value) == Real::not_a_number)
                    throw MeshError(line_at(line_no) + shown(words[k]) + " is not a number");
            }
            ++(normal ? normals : texcoords);
        } else if (keyword == "f") {
            const uint64_t face = mesh.faces + 1;
            const auto place = [&] { return line_at(line_no) + "face " + number(face) + ": "; };
            if (n < 3) throw MeshError(line_at(line_no) + too_few_corners(face, n));
            corners.clear();
            for (size_t k = 1; k <= n; ++k) {
                const std::string_view corner = words[k];
                parts.clear();
                for (size_t start = 0;;) {
                    const size_t slash = corner.find('/', start);
                    parts.push_back(corner.substr(start, slash == std::string_view::npos ? slash : slash - start));
                    if (slash == std::string_view::npos) break;
                    start = slash + 1;
                }
                // v, v/vt, v/vt/vn, v//vn
                const bool form_ok = parts.size() <= 3 && !parts[0].empty() &&
                    (parts.size() != 2 || !parts[1].empty()) && (parts.size() != 3 || !parts[2].empty());
                if (!form_ok)
                    throw MeshError(place() + "corner " + shown(corner) + " is not v, v/vt, v/vt/vn or v//vn");
                const auto resolve = [&](std::string_view word, uint64_t defined, Reference& max,
                                         const char* what) -> uint64_t {
                    int64_t i = 0;
                    if (!parse_int(word, i))
                        throw MeshError(place() + "corner " + shown(corner) + ": " + shown(word) + " is not an index");
                    if (i == 0)
                        throw MeshError(place() + "corner " + shown(corner) + ": " + what +
                                        " index 0 (OBJ counts from 1)");
                    if (i < 0) {
                        if (uint64_t(-(i + 1)) >= defined)
                            throw MeshError(place() + "refers to " + what + " " + std::to_string(i) + " but only " +
                                            number(defined) + " precede it");
                        return defined - uint64_t(-(i + 1)) - 1;
                    }
                    if (uint64_t(i) > max.index) max = {uint64_t(i), line_no, face};
                    return uint64_t(i) - 1;
                };
                const uint64_t v = resolve(parts[0], mesh.vertices.size(), max_vertex, "vertex");
                if (v >= kMaxIndex) throw MeshError(place() + "vertex index " + shown(parts[0]) + " is beyond 32 bits");
                if (parts.size() >= 2 && !parts[1].empty())
                    resolve(parts[1], texcoords, unchecked, "texture coordinate");
                if (parts.size() == 3) resolve(parts[2], normals, unchecked, "normal");
                corners.push_back(uint32_t(v));
            }
            mesh.add_face(corners);
        } else if (!obj_statement_without_triangles(keyword)) {
            throw MeshError(line_at(line_no) + "unknown statement " + shown(keyword) + " (not OBJ)");
        }
    }
    if (max_vertex.index > mesh.vertices.size())
        throw MeshError(line_at(max_vertex.line) + "face " + number(max_vertex.face) + " refers to vertex " +
                        number(max_vertex.index) + " but the file has " + number(mesh.vertices.size()) +
                        " vertices (OBJ counts from 1)");
}

// ---- PLY (Greg Turk, "The PLY Polygon File Format", 1994) -----------------------------
//
// Header: "ply", "format ascii|binary_little_endian|binary_big_endian 1.0", then
// "comment ..." / "obj_info ..." lines, "element NAME COUNT" each followed by its
// "property TYPE NAME" or "property list COUNT_TYPE ITEM_TYPE NAME" lines, and
// "end_header". Types: char uchar short ushort int uint float double and their sized
// names int8 uint8 int16 uint16 int32 uint32 float32 float64. Data: the elements in header
// order; ASCII has one element per line, every value of its type; binary is packed. We
// need element "vertex" with scalar x, y, z and element "face" with a list vertex_indices
// (or vertex_index); every other element and property is read and checked, then skipped.

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

bool ply_type(std::string_view name, PlyType& type) {
    static const std::pair<std::string_view, PlyType> names[] = {
        {"char", PlyType::i8},   {"int8", PlyType::i8},     {"uchar", PlyType::u8},   {"uint8", PlyType::u8},
        {"short", PlyType::i16}, {"int16", PlyType::i16},   {"ushort", PlyType::u16}, {"uint16", PlyType::u16},
        {"int", PlyType::i32},   {"int32", PlyType::i32},   {"uint", PlyType::u32},   {"uint32", PlyType::u32},
        {"float", PlyType::f32}, {"float32", PlyType::f32}, {"double", PlyType::f64}, {"float64", PlyType::f64}};
    for (const auto& [n, t] : names)
        if (n == name) {
            type = t;
            return true;
        }
    return false;
}
size_t ply_size(PlyType t) {
    switch (t) {
        case PlyType::i8:
        case PlyType::u8: return 1;
        case PlyType::i16:
        case PlyType::u16: return 2;
        case PlyType::i32:
        case PlyType::u32:
        case PlyType::f32: return 4;
        case PlyType::f64: return 8;
    }
    return 0;
}
bool ply_integer(PlyType t) { return t != PlyType::f32 && t != PlyType::f64; }
std::pair<int64_t, int64_t> ply_range(PlyType t) {
    switch (t) {
        case PlyType::i8: return {-128, 127};
        case PlyType::u8: return {0, 255};
        case PlyType::i16: return {-32768, 32767};
        case PlyType::u16: return {0, 65535};
        case PlyType::i32: return {INT32_MIN, INT32_MAX};
        default: return {0, UINT32_MAX};
    }
}

struct PlyProperty {
    std::string name;
    bool list = false;
    PlyType count_type = PlyType::u8;
    PlyType type = PlyType::f32;
};
struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

// One value of the data, as read: integers exactly, floats as the file's float or double.
struct PlyValue {
    int64_t integer = 0;
    double real = 0;
    float single = 0;  // for f32: the file's float bit for bit
};

class PlyReader {
public:
    PlyReader(std::string_view bytes, FlatMesh& mesh) : bytes_(bytes), mesh_(mesh) {}

    void read() {
        Lines lines(bytes_);
        read_header(lines);
        locate_needed();
        if (format_ == "ascii") read_ascii(lines);
        else read_binary();
    }

private:
    void read_header(Lines& lines) {
        std::string_view line;
        lines.next(line);
        if (line != "ply") throw MeshError("not a PLY file (the first line is not 'ply')");
        // Binary data starts right after "end_header" and the same line ending as "ply"'s.
        ending_ = bytes_.substr(3, lines.offset() - 3);
        std::vector<std::string_view> words;
        bool have_format = false;
        while (lines.next(line)) {
            const std::string place = line_at(lines.number());
            split_words(line, words);
            if (words.empty()) throw MeshError(place + "an empty header line");
            const std::string_view keyword = words[0];
            if (!have_format) {
                if (keyword != "format" || words.size() != 3)
                    throw MeshError(place + "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
                format_ = std::string(words[1]);
                if (format_ != "ascii" && format_ != "binary_little_endian" && format_ != "binary_big_endian")
                    throw MeshError(place + "unknown format " + shown(words[1]));
                if (words[2] != "1.0")
                    throw MeshError(place + "unsupported PLY version " + shown(words[2]) + " (1.0 is)");
                have_format = true;
            } else if (keyword == "comment" || keyword == "obj_info") {
                continue;
            } else if (keyword == "element") {
                int64_t count = 0;
                if (words.size() != 3 || !parse_int(words[2], count) || count < 0)
                    throw MeshError(place + "expected 'element NAME COUNT'");
                for (const PlyElement& e : elements_)
                    if (e.name == words[1]) throw MeshError(place + "a second element " + shown(words[1]));
                elements_.push_back({std::string(words[1]), uint64_t(count), {}});
            } else if (keyword == "property") {
                if (elements_.empty()) throw MeshError(place + "a property before any element");
                PlyProperty p;
                const bool ok = words.size() >= 2 && words[1] == "list"
                    ? words.size() == 5 && ply_type(words[2], p.count_type) && ply_integer(p.count_type) &&
                        ply_type(words[3], p.type)
                    : words.size() == 3 && ply_type(words[1], p.type);
                if (!ok)
                    throw MeshError(place +
                                    "expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME' "
                                    "(an integer COUNT_TYPE; types: char uchar short ushort int uint float double, "
                                    "or int8 ... float64)");
                p.list = words.size() == 5;
                p.name = std::string(words.back());
                for (const PlyProperty& q : elements_.back().properties)
                    if (q.name == p.name) throw MeshError(place + "a second property " + shown(p.name));
                elements_.back().properties.push_back(p);
            } else if (keyword == "end_header") {
                if (words.size() != 1) throw MeshError(place + "'end_header' followed by more");
                if (format_ != "ascii") {
                    const size_t at = size_t(line.data() - bytes_.data()) + line.size();
                    if (bytes_.substr(at, ending_.size()) != ending_)
                        throw MeshError(place +
                                        "'end_header' does not end like the 'ply' line, so where the binary "
                                        "data begins is ambiguous");
                    data_ = at + ending_.size();
                }
                return;
            } else {
                throw MeshError(place + "unknown header line " + shown(keyword));
            }
        }
        throw MeshError("corrupt PLY header (no 'end_header' line)");
    }

    void locate_needed() {
        for (size_t e = 0; e < elements_.size(); ++e) {
            const PlyElement& el = elements_[e];
            if (el.name == "vertex") {
                vertex_element_ = int(e);
                if (el.count > kMaxIndex) throw MeshError("the header declares more than 4294967295 vertices");
                for (int k = 0; k < 3; ++k) {
                    const char* axis[] = {"x", "y", "z"};
                    for (size_t p = 0; p < el.properties.size(); ++p)
                        if (el.properties[p].name == axis[k]) xyz_[k] = int(p);
                    if (xyz_[k] < 0 || el.properties[size_t(xyz_[k])].list)
                        throw MeshError(std::string("element vertex has no scalar property ") + axis[k]);
                }
            } else if (el.name == "face") {
                face_element_ = int(e);
                for (size_t p = 0; p < el.properties.size(); ++p) {
                    const PlyProperty& prop = el.properties[p];
                    if (prop.name != "vertex_indices" && prop.name != "vertex_index") continue;
                    if (indices_ >= 0) throw MeshError("element face has both vertex_indices and vertex_index");
                    if (!prop.list || !ply_integer(prop.type))
                        throw MeshError("face property " + prop.name + " is not a list of integers");
                    indices_ = int(p);
                }
                if (indices_ < 0) throw MeshError("element face has no list property vertex_indices");
            }
        }
        if (vertex_element_ < 0) throw MeshError("the header has no 'element vertex'");
        if (face_element_ < 0) throw MeshError("the header has no 'element face' (no triangles)");
        const uint64_t vertices = elements_[size_t(vertex_element_)].count;
        // Headers can lie (a corrupt count): reserve no more than the file could hold.
        mesh_.vertices.reserve(std::min<uint64_t>(vertices, bytes_.size() / 3));
        mesh_.triangles.reserve(std::min<uint64_t>(elements_[size_t(face_element_)].count, bytes_.size() / 4));
    }

    // "vertex 4" as faces refer to it (from 0), "face 5" the fifth (from 1), and so on.
    std::string instance(const PlyElement& el, uint64_t i) const {
        return el.name + " " + number(i + (&el == &elements_[size_t(vertex_element_)] ? 0 : 1));
    }
    static std::string plural(const PlyElement& el) { return el.name == "vertex" ? "vertices" : el.name + "s"; }

    // What one element instance's values mean for the mesh, once read.
    template <class Place>
    void take(size_t e, uint64_t i, const std::vector<PlyValue>& scalars, const std::vector<int64_t>& list,
              const Place& place) {
        if (int(e) == vertex_element_) {
            const PlyElement& el = elements_[e];
            float xyz[3];
            for (int k = 0; k < 3; ++k) {
                const PlyValue& v = scalars[size_t(xyz_[k])];
                const PlyType t = el.properties[size_t(xyz_[k])].type;
                if (t == PlyType::f32) xyz[k] = v.single;
                else if (t == PlyType::f64) {
                    if (std::isfinite(v.real) && std::fabs(v.real) > double(std::numeric_limits<float>::max()))
                        throw MeshError(place() + "vertex " + number(i) + ": coordinate " + std::to_string(v.real) +
                                        " is too large for a float");
                    xyz[k] = float(v.real);
                } else xyz[k] = float(v.integer);
            }
            mesh_.add_vertex({xyz[0], xyz[1], xyz[2]}, [&] { return place() + "vertex " + number(i) + ": "; });
        } else if (int(e) == face_element_) {
            const uint64_t face = i + 1;
            if (list.size() < 3) throw MeshError(place() + too_few_corners(face, list.size()));
            const uint64_t vertices = elements_[size_t(vertex_element_)].count;
            corners_.clear();
            for (int64_t v : list) {
                if (v < 0 || uint64_t(v) >= vertices)
                    throw MeshError(place() + "face " + number(face) + " refers to vertex " + std::to_string(v) +
                                    " but the file has " + number(vertices) + " vertices (PLY counts from 0)");
                corners_.push_back(uint32_t(v));
            }
            mesh_.add_face(corners_);
        }
    }

    void read_ascii(Lines& lines) {
        std::vector<std::string_view> words;
        std::vector<PlyValue> scalars;
        std::vector<int64_t> list;
        std::string_view line;
        const auto value = [&](std::string_view word, PlyType t, const auto& place) {
            PlyValue v;
            if (ply_integer(t)) {
                const auto [lo, hi] = ply_range(t);
                if (!parse_int(word, v.integer) || v.integer < lo || v.integer > hi)
                    throw MeshError(place() + shown(word) + " is not a value of its integer type (" +
                                    std::to_string(lo) + " to " + std::to_string(hi) + ")");
            } else if (t == PlyType::f32) {
                const Real r = parse_float(word, v.single);
                if (r == Real::not_a_number) throw MeshError(place() + shown(word) + " is not a number");
                if (r == Real::too_large) throw MeshError(place() + shown(word) + " is too large for a float");
            } else {
                const Real r = parse_double(word, v.real);
                if (r == Real::not_a_number) throw MeshError(place() + shown(word) + " is not a number");
                if (r == Real::too_large) throw MeshError(place() + shown(word) + " is too large for a double");
            }
            return v;
        };
        for (size_t e = 0; e < elements_.size(); ++e) {
            const PlyElement& el = elements_[e];
            if (el.properties.empty()) continue;  // no values to read
            for (uint64_t i = 0; i < el.count; ++i) {
                do {
                    if (!lines.next(line))
                        throw MeshError("the file ends before " + instance(el, i) + " (of " + number(el.count) + " " +
                                        plural(el) + " the header declares): it is cut short");
                    split_words(line, words);
                } while (words.empty());
                const uint64_t line_no = lines.number();
                const auto place = [&] { return line_at(line_no); };
                scalars.assign(el.properties.size(), PlyValue{});
                list.clear();
                size_t w = 0;
                for (size_t p = 0; p < el.properties.size(); ++p) {
                    const PlyProperty& prop = el.properties[p];
                    const auto where = [&] { return place() + instance(el, i) + ", property " + prop.name + ": "; };
                    if (w >= words.size()) throw MeshError(where() + "the line ends before this property (cut short?)");
                    if (!prop.list) {
                        scalars[p] = value(words[w++], prop.type, where);
                        continue;
                    }
                    const int64_t count = value(words[w++], prop.count_type, where).integer;
                    if (count < 0) throw MeshError(where() + "a negative list length");
                    if (uint64_t(count) > words.size() - w)
                        throw MeshError(where() + "the list has " + std::to_string(count) +
                                        " values but the line holds " + number(words.size() - w));
                    for (int64_t k = 0; k < count; ++k) {
                        const PlyValue item = value(words[w++], prop.type, where);
                        if (int(p) == indices_ && int(e) == face_element_) list.push_back(item.integer);
                    }
                }
                if (w != words.size())
                    throw MeshError(place() + instance(el, i) + " has " + number(words.size() - w) +
                                    " more values than its properties (one element per line)");
                take(e, i, scalars, list, place);
            }
        }
        while (lines.next(line)) {
            split_words(line, words);
            if (!words.empty())
                throw MeshError(line_at(lines.number()) + "more data after the last element the header declares");
        }
    }

    void read_binary() {
        const bool swap = (format_ == "binary_big_endian") != (std::endian::native == std::endian::big);
        size_t pos = data_;
        std::vector<PlyValue> scalars;
        std::vector<int64_t> list;
        const auto value = [&](PlyType t, const PlyElement& el, uint64_t i) {
            const size_t size = ply_size(t);
            if (bytes_.size() - pos < size)
                throw MeshError(byte_at(pos) + "the file ends inside " + instance(el, i) + " (of " + number(el.count) +
                                " " + plural(el) + " the header declares): it is cut short");
            // The value's bytes in host order (ply_size is at most 8). Copied byte by byte
            // rather than with std::reverse, which GCC 12's -march=native vectoriser warns
            // about (a -Wstringop-overflow false positive).
            unsigned char raw[8] = {};
            const auto* src = reinterpret_cast<const unsigned char*>(bytes_.data() + pos);
            for (size_t k = 0; k < size && k < sizeof raw; ++k) raw[k] = swap ? src[size - 1 - k] : src[k];
            pos += size;
            PlyValue v;
            switch (t) {
                case PlyType::i8: v.integer = int8_t(raw[0]); break;
                case PlyType::u8: v.integer = raw[0]; break;
                case PlyType::i16: {
                    int16_t x;
                    std::memcpy(&x, raw, 2);
                    v.integer = x;
                    break;
                }
                case PlyType::u16: {
                    uint16_t x;
                    std::memcpy(&x, raw, 2);
                    v.integer = x;
                    break;
                }
                case PlyType::i32: {
                    int32_t x;
                    std::memcpy(&x, raw, 4);
                    v.integer = x;
                    break;
                }
                case PlyType::u32: {
                    uint32_t x;
                    std::memcpy(&x, raw, 4);
                    v.integer = x;
                    break;
                }
                case PlyType::f32:
                    std::memcpy(&v.single, raw, 4);
                    v.real = v.single;
                    break;
                case PlyType::f64: std::memcpy(&v.real, raw, 8); break;
            }
            return v;
        };
        for (size_t e = 0; e < elements_.size(); ++e) {
            const PlyElement& el = elements_[e];
            if (el.properties.empty()) continue;  // no bytes to read
            // The smallest an instance can be (lists empty): a count no file of this size holds
            // is refused before reading.
            size_t least = 0;
            for (const PlyProperty& p : el.properties) least += ply_size(p.list ? p.count_type : p.type);
            if (least > 0 && el.count > (bytes_.size() - pos) / least)
                throw MeshError(byte_at(pos) + "the header declares " + number(el.count) + " " + plural(el) +
                                ", at least " + number(least) + " bytes each, but only " + number(bytes_.size() - pos) +
                                " bytes follow: it is cut short or its header is corrupt");
            for (uint64_t i = 0; i < el.count; ++i) {
                const size_t start = pos;
                scalars.assign(el.properties.size(), PlyValue{});
                list.clear();
                for (size_t p = 0; p < el.properties.size(); ++p) {
                    const PlyProperty& prop = el.properties[p];
                    if (!prop.list) {
                        scalars[p] = value(prop.type, el, i);
                        continue;
                    }
                    const int64_t count = value(prop.count_type, el, i).integer;
                    if (count < 0)
                        throw MeshError(byte_at(start) + instance(el, i) + ", property " + prop.name +
                                        ": a negative list length");
                    for (int64_t k = 0; k < count; ++k) {
                        const PlyValue item = value(prop.type, el, i);
                        if (int(p) == indices_ && int(e) == face_element_) list.push_back(item.integer);
                    }
                }
                take(e, i, scalars, list, [&] { return byte_at(start); });
            }
        }
        if (pos != bytes_.size())
            throw MeshError(byte_at(pos) + number(bytes_.size() - pos) +
                            " bytes after the last element the header declares");
    }

    std::string_view bytes_;
    FlatMesh& mesh_;
    std::string format_;
    std::string_view ending_;  // of the "ply" line: LF, CR LF or CR
    size_t data_ = 0;          // binary: the first byte after the header
    std::vector<PlyElement> elements_;
    int vertex_element_ = -1, face_element_ = -1, indices_ = -1;
    int xyz_[3] = {-1, -1, -1};
    std::vector<uint32_t> corners_;
};

// ---- OFF (Geomview, "OFF Files", the OOGL file formats) ----------------------------------
//
// "[ST][C][N]OFF" (optional: files without it start with the counts), then "NVertices
// NFaces NEdges" (NEdges must be present, its value is not used), NVertices vertices and
// NFaces faces "N v1 ... vN [colour]"; '#' starts a comment to the end of the line. We read
// one vertex per line: x y z, then 3 normal numbers with N, 3 or 4 colour numbers with C, 2
// texture coordinates with ST, in that order. A face's colour is 0 to 4 numbers to the end
// of its line. 4OFF (homogeneous), nOFF (n dimensions) and binary OFF are refused.
void read_off(std::string_view text, FlatMesh& mesh) {
    Lines lines(text);
    std::vector<std::string_view> words;
    std::string_view line;
    // The next line with words, comments removed; false at the end of the file.
    const auto next_words = [&]() {
        while (lines.next(line)) {
            split_words(strip_comment(line), words);
            if (!words.empty()) return true;
        }
        return false;
    };
    if (!next_words()) throw MeshError("empty OFF file");
    size_t w = 0;
    bool normals = false, colours = false, texcoords = false;
    const std::string keyword(words[0]);
    if (keyword.size() >= 3 && keyword.compare(keyword.size() - 3, 3, "OFF") == 0) {
        std::string_view prefix = std::string_view(keyword).substr(0, keyword.size() - 3);
        const auto take_prefix = [&](std::string_view p) {
            if (prefix.substr(0, p.size()) != p) return false;
            prefix.remove_prefix(p.size());
            return true;
        };
        texcoords = take_prefix("ST");
        colours = take_prefix("C");
        normals = take_prefix("N");
        if (take_prefix("4") || take_prefix("n"))
            throw MeshError(line_at(lines.number()) + shown(keyword) +
                            ": 4OFF and nOFF (vertices of other than 3 components) are not supported");
        if (!prefix.empty()) throw MeshError(line_at(lines.number()) + "not an OFF header keyword " + shown(keyword));
        w = 1;
        if (w < words.size() && words[w] == "BINARY")
            throw MeshError(line_at(lines.number()) + "binary OFF is not supported (ASCII OFF is)");
    }
    int64_t counts[3];
    for (int k = 0; k < 3; ++k) {
        if (w == words.size()) {
            if (!next_words()) throw MeshError("the file ends in the header (expected 'NVertices NFaces NEdges')");
            w = 0;
        }
        if (!parse_int(words[w], counts[k]) || counts[k] < 0)
            throw MeshError(line_at(lines.number()) +
                            (w == 0 && k == 0 && lines.number() == 1 ? "not an OFF file: " : "") +
                            "expected 'NVertices NFaces NEdges' (three integers), found " + shown(words[w]));
        ++w;
    }
    if (w != words.size()) throw MeshError(line_at(lines.number()) + "more after 'NVertices NFaces NEdges'");
    const uint64_t vertices = uint64_t(counts[0]), faces = uint64_t(counts[1]);
    if (vertices > kMaxIndex) throw MeshError("the header declares more than 4294967295 vertices");
    mesh.vertices.reserve(std::min<uint64_t>(vertices, text.size() / 6));
    mesh.triangles.reserve(std::min<uint64_t>(faces, text.size() / 8));

    const size_t least = 3 + (normals ? 3 : 0) + (colours ? 3 : 0) + (texcoords ? 2 : 0);
    const size_t most = least + (colours ? 1 : 0);
    for (uint64_t i = 0; i < vertices; ++i) {
        if (!next_words())
            throw MeshError("the file ends before vertex " + number(i) + " (of " + number(vertices) +
                            "): it is cut short");
        const uint64_t line_no = lines.number();
        const auto place = [&] { return line_at(line_no) + "vertex " + number(i) + ": "; };
        if (words.size() < least || words.size() > most)
            throw MeshError(place() + number(words.size()) + " numbers on the line, " + shown(keyword) +
                            " vertices have " + number(least) + (most > least ? " or " + number(most) : "") +
                            " (one vertex per line)");
        for (size_t k = 3; k < words.size(); ++k) {
            float ignored;
            if (parse_float(words[k], ignored) == Real::not_a_number)
                throw MeshError(place() + shown(words[k]) + " is not a number");
        }
        mesh.add_vertex(coordinates(words.data(), place), place);
    }
    std::vector<uint32_t> corners;
    for (uint64_t f = 1; f <= faces; ++f) {
        if (!next_words())
            throw MeshError("the file ends before face " + number(f) + " (of " + number(faces) + "): it is cut short");
        const uint64_t line_no = lines.number();
        const auto place = [&] { return line_at(line_no) + "face " + number(f) + ": "; };
        int64_t n = 0;
        if (!parse_int(words[0], n) || n < 0) throw MeshError(place() + shown(words[0]) + " is not a corner count");
        if (n < 3) throw MeshError(line_at(lines.number()) + too_few_corners(f, uint64_t(n)));
        if (uint64_t(n) > words.size() - 1)
            throw MeshError(place() + "it has " + std::to_string(n) + " corners but the line holds " +
                            number(words.size() - 1) + " indices (one face per line)");
        if (words.size() - 1 - uint64_t(n) > 4)
            throw MeshError(place() + number(words.size() - 1 - uint64_t(n)) +
                            " numbers after its corners (a colour is 0 to 4 numbers)");
        corners.clear();
        for (int64_t k = 1; k <= n; ++k) {
            int64_t v = 0;
            if (!parse_int(words[size_t(k)], v))
                throw MeshError(place() + shown(words[size_t(k)]) + " is not a vertex index");
            if (v < 0 || uint64_t(v) >= vertices)
                throw MeshError(place() + "refers to vertex " + std::to_string(v) + " but the file has " +
                                number(vertices) + " vertices (OFF counts from 0)");
            corners.push_back(uint32_t(v));
        }
        for (size_t k = size_t(n) + 1; k < words.size(); ++k) {
            float ignored;
            if (parse_float(words[k], ignored) == Real::not_a_number)
                throw MeshError(place() + "colour " + shown(words[k]) + " is not a number");
        }
        mesh.add_face(corners);
    }
    if (next_words()) throw MeshError(line_at(lines.number()) + "more data after the last face the header declares");
}

// ---- STL (3D Systems, "StereoLithography Interface Specification", 1989) ----------------
//
// Binary: an 80-byte header, a little-endian uint32 triangle count, 50 bytes per triangle
// (normal, three corners as float32, a uint16 attribute). Chosen when the size is exactly
// 84 + 50 * count (a binary header may itself begin with "solid"). ASCII: "solid NAME",
// then per triangle "facet normal n n n / outer loop / vertex x y z (three times) /
// endloop / endfacet", then "endsolid NAME"; keywords in any case, words separated by any
// blanks or line ends, NAME the rest of its line. Several solids in a row are read as one
// mesh. STL repeats corners: equal positions become one vertex (in order of first use).
class StlVertices {
public:
    explicit StlVertices(FlatMesh& mesh) : mesh_(mesh) {}
    template <class Place>
    uint32_t index(Vec3 p, const Place& place) {
        if (!within_coordinate_limit(p)) throw MeshError(place() + vertex_problem(p));
        const auto bits = [](float c) { return std::bit_cast<uint32_t>(c == 0.0f ? 0.0f : c); };  // -0 is 0
        const Key key{bits(p.x), bits(p.y), bits(p.z)};
        const auto [it, added] = index_.try_emplace(key, uint32_t(mesh_.vertices.size()));
        if (added) mesh_.add_vertex(p, place);
        return it->second;
    }

private:
    using Key = std::array<uint32_t, 3>;
    struct Hash {
        size_t operator()(const Key& k) const {
            return size_t((uint64_t(k[0]) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(k[1]) * 0xC2B2AE3D27D4EB4Full) ^
                          (uint64_t(k[2]) * 0x165667B19E3779F9ull));
        }
    };
    FlatMesh& mesh_;
    std::unordered_map<Key, uint32_t, Hash> index_;
};

void read_binary_stl(std::string_view bytes, uint64_t count, FlatMesh& mesh) {
    StlVertices vertices(mesh);
    mesh.triangles.reserve(count);
    std::vector<uint32_t> corners(3);
    for (uint64_t t = 0; t < count; ++t) {
        const size_t at = 84 + 50 * t;
        for (int c = 0; c < 3; ++c) {
            float xyz[3];
            std::memcpy(xyz, bytes.data() + at + 12 * (c + 1), 12);
            if constexpr (std::endian::native == std::endian::big)
                for (float& v : xyz) v = std::bit_cast<float>(byte_swapped(std::bit_cast<uint32_t>(v)));
            corners[size_t(c)] = vertices.index({xyz[0], xyz[1], xyz[2]}, [&] {
                return byte_at(at) + "triangle " + number(t + 1) + ", corner " + number(c + 1) + ": ";
            });
        }
        mesh.add_face(corners);
    }
}

void read_ascii_stl(std::string_view text, FlatMesh& mesh, const std::string& binary_hint) {
    Lines lines(text);
    std::vector<std::string_view> words;
    size_t w = 0;
    std::string_view line;
    bool more = true;
    // The next word, across lines; "" at the end of the file.
    const auto word = [&]() -> std::string_view {
        while (w == words.size()) {
            if (!lines.next(line)) {
                more = false;
                return {};
            }
            split_words(line, words);
            w = 0;
        }
        return words[w++];
    };
    const auto rest_of_line = [&]() { w = words.size(); };
    const auto expect = [&](const char* keyword, uint64_t triangle) {
        const std::string_view got = word();
        if (lowercase(got) == keyword) return;
        const std::string in = triangle ? "triangle " + number(triangle) + ": " : "";
        if (!more)
            throw MeshError("the file ends in " + in + "expected '" + keyword + "': it is cut short" + binary_hint);
        throw MeshError(line_at(lines.number()) + in + "expected '" + keyword + "', found " + shown(got) + binary_hint);
    };
    StlVertices vertices(mesh);
    std::vector<uint32_t> corners(3);
    uint64_t triangle = 0;
    expect("solid", 0);
    rest_of_line();  // the name
    for (;;) {
        const std::string_view got = word();
        const std::string keyword = lowercase(got);
        if (!more) throw MeshError("the file ends without 'endsolid': it is cut short");
        if (keyword == "endsolid") {
            rest_of_line();
            const std::string_view next = word();
            if (!more) return;
            if (lowercase(next) != "solid")
                throw MeshError(line_at(lines.number()) +
                                "expected 'solid' or the end of the file after 'endsolid', found " + shown(next));
            rest_of_line();
            continue;
        }
        if (keyword != "facet")
            throw MeshError(line_at(lines.number()) + "expected 'facet' or 'endsolid', found " + shown(got) +
                            binary_hint);
        ++triangle;
        expect("normal", triangle);
        for (int k = 0; k < 3; ++k) {
            float ignored;  // the normal is not used (and may be anything numeric, as writers leave it 0 or NaN)
            const std::string_view n = word();
            if (!more) throw MeshError("the file ends in triangle " + number(triangle) + "'s normal: it is cut short");
            if (parse_float(n, ignored) == Real::not_a_number)
                throw MeshError(line_at(lines.number()) + "triangle " + number(triangle) + ": normal " + shown(n) +
                                " is not a number");
        }
        expect("outer", triangle);
        expect("loop", triangle);
        for (int c = 0; c < 3; ++c) {
            expect("vertex", triangle);
            std::string_view xyz[3];
            for (auto& x : xyz) x = word();
            if (!more) throw MeshError("the file ends in triangle " + number(triangle) + ": it is cut short");
            const auto place = [&] {
                return line_at(lines.number()) + "triangle " + number(triangle) + ", corner " + number(c + 1) + ": ";
            };
            corners[size_t(c)] = vertices.index(coordinates(xyz, place), place);
        }
        expect("endloop", triangle);
        expect("endfacet", triangle);
        mesh.add_face(corners);
    }
}

void read_stl(std::string_view bytes, FlatMesh& mesh) {
    std::string hint;
    if (bytes.size() >= 84) {
        uint32_t declared = 0;
        std::memcpy(&declared, bytes.data() + 80, 4);
        if constexpr (std::endian::native == std::endian::big) declared = byte_swapped(declared);
        if (84 + 50 * uint64_t(declared) == bytes.size()) return read_binary_stl(bytes, declared, mesh);
        hint = " (as binary STL it would declare " + number(declared) + " triangles, " +
            number(84 + 50 * uint64_t(declared)) + " bytes, but the file has " + number(bytes.size()) + ")";
    }
    const size_t first = bytes.find_first_not_of(" \t\r\n\v\f");
    if (first == std::string_view::npos || lowercase(bytes.substr(first, 5)) != "solid" ||
        (bytes.size() > first + 5 && !std::isspace(static_cast<unsigned char>(bytes[first + 5]))))
        throw MeshError("corrupt STL: it does not start with 'solid' as ASCII STL does" +
                        (hint.empty() ? " and is too short for binary STL" : hint));
    read_ascii_stl(bytes, mesh, hint);
}

// ---- reading the bytes ---------------------------------------------------------------

std::string read_file(const std::string& path) {
    std::error_code ec;
    const uint64_t size = fs::file_size(path, ec);
    if (ec) fail(path, "cannot read its size (" + ec.message() + ")");
    if (size > kMaxMeshFileBytes) fail(path, "larger than 4 GiB, the limit (files are read into memory whole)");
    std::ifstream in(path, std::ios::binary);
    std::string bytes(size_t(size), '\0');
    if (!in.read(bytes.data(), std::streamsize(size)) || in.gcount() != std::streamsize(size))
        fail(path, "reading it failed");
    return bytes;
}

std::string gunzip(const std::string& path) {
    gzFile in = gzopen(path.c_str(), "rb");
    if (!in) fail(path, "cannot open it for reading");
    std::string bytes, error;
    std::vector<char> buffer(1 << 18);
    for (bool first = true;; first = false) {
        const int n = gzread(in, buffer.data(), unsigned(buffer.size()));
        if (first && gzdirect(in)) {
            error = "it is named .gz but is not gzip-compressed";
            break;
        }
        if (n < 0) {
            int code = 0;
            error = std::string("corrupt gzip data (") + gzerror(in, &code) + ")";
            break;
        }
        if (n == 0) break;
        if (bytes.size() + size_t(n) > kMaxMeshFileBytes) {
            error = "it decompresses to more than 4 GiB, the limit (files are read into memory whole)";
            break;
        }
        bytes.append(buffer.data(), size_t(n));
    }
    // gzclose_r reports a stream that ended in the middle (a truncated download).
    const int closed = gzclose_r(in);
    if (error.empty() && closed != Z_OK) error = "truncated or corrupt gzip data";
    if (!error.empty()) fail(path, error);
    return bytes;
}

std::string file_kind(fs::file_type type) {
    switch (type) {
        case fs::file_type::directory: return "a directory";
        case fs::file_type::fifo: return "a FIFO";
        case fs::file_type::socket: return "a socket";
        case fs::file_type::block: return "a block device";
        case fs::file_type::character: return "a character device";
        default: return "not a file";
    }
}

}  // namespace

Scene parse_mesh(std::string_view bytes, const std::string& format, const std::string& shown_as,
                 MeshLoadInfo* info_out) {
    FlatMesh mesh;
    try {
        if (format == "obj") read_obj(bytes, mesh);
        else if (format == "ply") PlyReader(bytes, mesh).read();
        else if (format == "off") read_off(bytes, mesh);
        else if (format == "stl") read_stl(bytes, mesh);
        else throw MeshError("unsupported format '" + format + "' (supported: obj ply off stl)");
    } catch (const MeshError& e) {
        fail(shown_as, e.what());
    }
    if (mesh.triangles.empty()) fail(shown_as, "empty mesh (no triangles)");

    Scene scene;
    fs::path stem = fs::path(shown_as).filename();
    if (lowercase(stem.extension().string()) == ".gz") stem = stem.stem();
    scene.name = stem.stem().string();
    scene.vertices = std::move(mesh.vertices);
    scene.triangles = std::move(mesh.triangles);
    scene.finalize();  // cannot fail: every index and vertex was checked
    if (info_out) {
        info_out->format = format;
        info_out->file_faces = mesh.faces;
        info_out->polygons = mesh.polygons;
        info_out->triangles = scene.triangle_count();
        info_out->vertices = scene.vertex_count();
    }
    return scene;
}

Scene load_mesh(const std::string& path, MeshLoadInfo* info_out) {
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) fail(path, "file not found");
    if (!fs::is_regular_file(status)) fail(path, "not a regular file (" + file_kind(status.type()) + ")");
    if (!std::ifstream(path, std::ios::binary)) fail(path, "file cannot be opened for reading");

    // "name.ply.gz" -> compressed, format "ply".
    fs::path inner = fs::path(path).filename();
    const bool compressed = lowercase(inner.extension().string()) == ".gz";
    if (compressed) inner = inner.stem();
    std::string format = lowercase(inner.extension().string());
    if (!format.empty()) format.erase(0, 1);
    if (format != "obj" && format != "ply" && format != "off" && format != "stl")
        fail(path, "unsupported file extension (supported: .obj .ply .off .stl, each optionally .gz)");

    const std::string bytes = compressed ? gunzip(path) : read_file(path);
    MeshLoadInfo info;
    Scene scene = parse_mesh(bytes, format, path, &info);
    info.compressed = compressed;
    if (info_out) *info_out = info;
    return scene;
}

// Written by hand: OpenMesh's PLY writer takes a half-edge mesh, which would drop the faces
// our importer keeps (see mesh_io.h), and writes no header comments.
void write_ply(const Scene& scene, const std::string& path, const std::vector<std::string>& comments) {
    static_assert(std::endian::native == std::endian::little, "write_ply writes the host's bytes as little-endian");
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + path);
    out << "ply\nformat binary_little_endian 1.0\n";
    for (const auto& c : comments) {
        if (c.find('\n') != std::string::npos || c.find('\r') != std::string::npos)
            throw std::invalid_argument("write_ply: a comment with a line break");
        out << "comment " << c << "\n";
    }
    out << "element vertex " << scene.vertex_count() << "\nproperty float x\nproperty float y\nproperty float z\n"
        << "element face " << scene.triangle_count() << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const Vec3& v : scene.vertices) {
        const float xyz[3] = {v.x, v.y, v.z};
        out.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
    }
    for (const auto& t : scene.triangles) {
        char face[1 + 3 * sizeof(int32_t)];
        face[0] = 3;
        for (int k = 0; k < 3; ++k) {
            const int32_t i = int32_t(t[size_t(k)]);
            std::memcpy(face + 1 + k * sizeof(int32_t), &i, sizeof i);
        }
        out.write(face, sizeof face);
    }
    out.close();
    if (!out) throw std::runtime_error("writing " + path + " failed");
}

// The header is plain text lines; OpenMesh's PLY reader skips its comments.
std::vector<std::string> read_ply_comments(const std::string& path) {
    std::vector<std::string> comments;
    std::ifstream in(path, std::ios::binary);
    std::string line;
    if (!std::getline(in, line) || line != "ply") return comments;
    while (std::getline(in, line) && line != "end_header")
        if (line.rfind("comment ", 0) == 0) comments.push_back(line.substr(8));
    return comments;
}

}  // namespace accelbench
