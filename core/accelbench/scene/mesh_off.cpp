#include "accelbench/scene/mesh_reading.h"

namespace accelbench::mesh_reading {

// ---- OFF (Geomview, "OFF Files", the OOGL file formats) ----------------------------------
//
// "[ST][C][N]OFF" (optional: files without it start with the counts), then "NVertices
// NFaces NEdges" on one line (NEdges must be present, its value is not used), NVertices vertices and
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
    // The three counts are one line (the keyword's or the next): a count missing is named
    // on that line, not found on a vertex's.
    if (w == words.size()) {
        if (!next_words()) throw MeshError("the file ends in the header (expected 'NVertices NFaces NEdges')");
        w = 0;
    }
    int64_t counts[3];
    for (int k = 0; k < 3; ++k) {
        if (w == words.size())
            throw MeshError(line_at(lines.number()) + "'NVertices NFaces NEdges' has " + number(uint64_t(k)) +
                            " of its 3 numbers (" + (k == 2 ? "NEdges is missing; " : "") +
                            "all three are one line, NEdges even when unused)");
        if (!parse_int(words[w], counts[k]) || counts[k] < 0)
            throw MeshError(line_at(lines.number()) +
                            (w == 0 && k == 0 && lines.number() == 1 ? "not an OFF file: " : "") +
                            "expected 'NVertices NFaces NEdges' (three integers), found " + shown(words[w]));
        ++w;
    }
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

}  // namespace accelbench::mesh_reading
