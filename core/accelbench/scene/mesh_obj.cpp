#include "accelbench/scene/mesh_reading.h"

namespace accelbench::mesh_reading {

namespace {

// ---- OBJ (Wavefront, "Object Files (.obj)", Appendix B1 of the Advanced Visualizer
// manual) -------------------------------------------------------------------------------
//
// A statement per line; a line ending in '\' continues on the next (a '\' ending a
// comment is the comment's); '#' starts a comment
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

}  // namespace

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
        // A '\\' ending a line continues it, unless it ends a comment: it is then the comment's.
        const auto continued = [](std::string_view l) {
            const size_t last = l.find_last_not_of(" \t\v\f");
            return last != std::string_view::npos && l[last] == '\\' && l.find('#') > last ? last
                                                                                           : std::string_view::npos;
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

}  // namespace accelbench::mesh_reading
