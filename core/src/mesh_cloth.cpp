// Cloth from an OBJ triangle mesh: reading (a checking pre-pass, then tinyobjloader), cleaning, placing. See
// core/include/drape/mesh_cloth.hpp for the rules.
#include "drape/mesh_cloth.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <sys/stat.h>
#include <unordered_map>

#include <tiny_obj_loader.h>

#include "drape/errors.hpp"

namespace drape {

namespace {

bool is_space(char c) noexcept { return c == ' ' || c == '\t' || c == '\r'; }

/// What the pre-pass finds: vertex positions exactly as written (strtod, correctly rounded, unlike tinyobjloader's
/// own reader, which also reads "nan" or "1e400" as 0 or inf without a word).
struct PrePass {
    std::vector<double> x, y, z;
};

/// One line of OBJ text at a time: vertices checked and read, face indices checked against the vertex count.
PrePass pre_pass(const std::string& text, const std::string& source, std::size_t max_vertices) {
    PrePass out;
    std::size_t line_no = 0, max_index = 0, max_index_line = 0;
    std::size_t pos = 0;
    auto fail = [&](const std::string& what) -> void {
        throw InvalidInput(source + ": line " + std::to_string(line_no) + ": " + what);
    };
    while (pos < text.size()) {
        ++line_no;
        std::size_t end = text.find('\n', pos);
        if (end == std::string::npos) end = text.size();
        const char* p = text.data() + pos;
        const char* const e = text.data() + end;
        pos = end + 1;
        while (p < e && is_space(*p)) ++p;
        if (e - p < 2 || !(p[0] == 'v' || p[0] == 'f') || !(p[1] == ' ' || p[1] == '\t')) continue;
        const bool vertex = p[0] == 'v';
        p += 2;
        // Tokens of the line (a copy, so strtod stops at the line's end).
        std::vector<std::string> tokens;
        while (p < e) {
            while (p < e && is_space(*p)) ++p;
            const char* t = p;
            while (p < e && !is_space(*p)) ++p;
            if (p > t) tokens.emplace_back(t, p);
        }
        if (vertex) {
            if (tokens.size() < 3) fail("a vertex needs 3 coordinates (v x y z), found " + std::to_string(tokens.size()));
            double c[3];
            for (int k = 0; k < 3; ++k) {
                char* stop = nullptr;
                errno = 0;
                c[k] = std::strtod(tokens[k].c_str(), &stop);
                if (stop == tokens[k].c_str() || *stop != '\0')
                    fail("vertex coordinate '" + tokens[k].substr(0, 40) + "' is not a number");
                if (!std::isfinite(c[k]) || std::fabs(c[k]) > 1e30)
                    fail("vertex coordinate '" + tokens[k].substr(0, 40) + "' is not a finite number (|x| <= 1e30)");
            }
            if (out.x.size() >= max_vertices)
                fail("more than " + std::to_string(max_vertices) + " vertices (a mesh cloth has at most " +
                     std::to_string(max_vertices) + " particles)");
            out.x.push_back(c[0]);
            out.y.push_back(c[1]);
            out.z.push_back(c[2]);
        } else {
            if (tokens.size() < 3) fail("a face needs at least 3 vertices, found " + std::to_string(tokens.size()));
            for (const std::string& t : tokens) {
                char* stop = nullptr;
                errno = 0;
                const long long i = std::strtoll(t.c_str(), &stop, 10);
                if (stop == t.c_str() || (*stop != '\0' && *stop != '/') || errno == ERANGE)
                    fail("face vertex '" + t.substr(0, 40) + "' is not a vertex index");
                const long long count = static_cast<long long>(out.x.size());
                if (i == 0) fail("face vertex index 0 (OBJ indices start at 1; negative ones count back)");
                if (i < 0 && -i > count)
                    fail("face vertex index " + std::to_string(i) + " reaches before the first vertex (" +
                         std::to_string(count) + " vertices so far)");
                if (i > 0 && static_cast<std::size_t>(i) > max_index) {
                    max_index = static_cast<std::size_t>(i);
                    max_index_line = line_no;
                }
            }
        }
    }
    if (max_index > out.x.size()) {
        line_no = max_index_line;
        fail("face vertex index " + std::to_string(max_index) + " is outside [1, " + std::to_string(out.x.size()) +
             "] (the file has " + std::to_string(out.x.size()) + " vertices)");
    }
    return out;
}

/// tinyobjloader's messages are "...\n" lists; the first non-material one, on one line.
std::string first_message(const std::string& messages) {
    std::istringstream in(messages);
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line == ".") continue;
        if (line.find("material") != std::string::npos || line.find(".mtl") != std::string::npos) continue;
        return line;
    }
    return "";
}

struct PositionKey {
    double x, y, z;
    bool operator==(const PositionKey& o) const noexcept { return x == o.x && y == o.y && z == o.z; }
};
struct PositionHash {
    std::size_t operator()(const PositionKey& k) const noexcept {
        auto bits = [](double d) {
            d = d == 0.0 ? 0.0 : d; // -0 and +0 are the same position
            std::uint64_t u;
            std::memcpy(&u, &d, sizeof u);
            return u;
        };
        std::uint64_t h = bits(k.x) * 0x9e3779b97f4a7c15ull;
        h ^= bits(k.y) + 0x7f4a7c159e3779b9ull + (h << 6) + (h >> 2);
        h ^= bits(k.z) + 0x94d049bb133111ebull + (h << 6) + (h >> 2);
        return static_cast<std::size_t>(h);
    }
};

double triangle_area2(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& z,
                      std::uint32_t a, std::uint32_t b, std::uint32_t c) noexcept {
    const double ux = x[b] - x[a], uy = y[b] - y[a], uz = z[b] - z[a];
    const double vx = x[c] - x[a], vy = y[c] - y[a], vz = z[c] - z[a];
    const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
    return std::sqrt(cx * cx + cy * cy + cz * cz); // twice the area
}

} // namespace

double TriangleMesh::area() const noexcept {
    double sum = 0.0;
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
        sum += 0.5 * triangle_area2(x, y, z, triangles[t], triangles[t + 1], triangles[t + 2]);
    return sum;
}

std::string TriangleMesh::cleaning_note() const {
    std::string note;
    auto add = [&](std::size_t count, const char* what) {
        if (count == 0) return;
        note += (note.empty() ? "" : ", ") + std::to_string(count) + " " + what;
    };
    add(degenerate, "degenerate triangles dropped (zero area or a repeated vertex)");
    add(repeated, "repeated triangles dropped");
    add(welded, "vertices welded to another at the same position");
    add(unused, "vertices in no triangle dropped");
    return note;
}

TriangleMesh parse_obj_mesh(const std::string& text, const std::string& source, std::size_t max_vertices) {
    // A UTF-8 byte order mark (some editors write one) is not part of the first line: read with it, the first "v"
    // line was dropped and every face index pointed one vertex on.
    if (text.rfind("\xEF\xBB\xBF", 0) == 0) return parse_obj_mesh(text.substr(3), source, max_vertices);
    PrePass pre = pre_pass(text, source, std::min(max_vertices, mesh_max_vertices));

    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    std::istringstream stream(text);
    const bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &stream, nullptr, true, false);
    const std::string error = first_message(err);
    if (!ok || !error.empty())
        throw InvalidInput(source + ": " + (error.empty() ? std::string("tinyobjloader could not read it") : error));
    const std::string warning = first_message(warn);
    if (!warning.empty()) throw InvalidInput(source + ": " + warning);
    const std::size_t nv = pre.x.size();
    if (attrib.vertices.size() != 3 * nv)
        throw InvalidInput(source + ": tinyobjloader read " + std::to_string(attrib.vertices.size() / 3) +
                           " vertices where the file has " + std::to_string(nv) + " 'v' lines");

    TriangleMesh m;
    // Weld vertices at exactly the same position (file order: the first one keeps the position).
    std::vector<std::uint32_t> weld(nv);
    {
        std::unordered_map<PositionKey, std::uint32_t, PositionHash> first;
        first.reserve(nv);
        for (std::size_t i = 0; i < nv; ++i) {
            const auto [it, inserted] = first.emplace(PositionKey{pre.x[i], pre.y[i], pre.z[i]}, std::uint32_t(i));
            weld[i] = it->second;
            m.welded += inserted ? 0 : 1;
        }
    }
    // Triangles over welded vertices; degenerate and repeated ones dropped.
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = 0; i < nv; ++i) {
        const double p[3] = {pre.x[i], pre.y[i], pre.z[i]};
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
    double diag2 = 0.0;
    for (int k = 0; k < 3 && nv > 0; ++k) diag2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    std::vector<std::uint32_t> kept;
    std::vector<std::array<std::uint32_t, 3>> sorted_kept;
    for (const tinyobj::shape_t& shape : shapes) {
        const auto& idx = shape.mesh.indices;
        for (std::size_t t = 0; t + 2 < idx.size(); t += 3) {
            ++m.obj_faces;
            std::uint32_t v[3];
            for (int k = 0; k < 3; ++k) {
                const int i = idx[t + k].vertex_index;
                if (i < 0 || static_cast<std::size_t>(i) >= nv)
                    throw InvalidInput(source + ": face vertex index " + std::to_string(i + 1) + " is outside [1, " +
                                       std::to_string(nv) + "]");
                v[k] = weld[static_cast<std::size_t>(i)];
            }
            if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2] ||
                !(triangle_area2(pre.x, pre.y, pre.z, v[0], v[1], v[2]) > 1e-12 * diag2)) {
                ++m.degenerate;
                continue;
            }
            std::array<std::uint32_t, 3> key{v[0], v[1], v[2]};
            std::sort(key.begin(), key.end());
            sorted_kept.push_back(key);
            kept.insert(kept.end(), {v[0], v[1], v[2]});
        }
    }
    // Repeated triangles (the same three vertices, any order or winding): keep the first.
    {
        std::vector<std::size_t> order(sorted_kept.size());
        for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
        std::stable_sort(order.begin(), order.end(),
                         [&](std::size_t a, std::size_t b) { return sorted_kept[a] < sorted_kept[b]; });
        std::vector<std::uint8_t> drop(sorted_kept.size(), 0);
        for (std::size_t k = 1; k < order.size(); ++k)
            if (sorted_kept[order[k]] == sorted_kept[order[k - 1]]) drop[order[k]] = 1;
        std::vector<std::uint32_t> unique;
        unique.reserve(kept.size());
        for (std::size_t k = 0; k < drop.size(); ++k) {
            if (drop[k]) {
                ++m.repeated;
                continue;
            }
            unique.insert(unique.end(), {kept[3 * k], kept[3 * k + 1], kept[3 * k + 2]});
        }
        kept.swap(unique);
    }
    if (kept.empty())
        throw InvalidInput(source + ": no triangle" +
                           (m.obj_faces == 0 ? std::string(" (the file has no faces: f lines)")
                                             : " left after dropping " + std::to_string(m.degenerate) +
                                                   " degenerate ones (zero area or a repeated vertex)") +
                           "; a mesh cloth needs triangles");
    // Particles: the vertices used by kept triangles, in file order.
    std::vector<std::uint8_t> used(nv, 0);
    for (std::uint32_t v : kept) used[v] = 1;
    std::vector<std::int64_t> particle(nv, -1);
    for (std::size_t i = 0; i < nv; ++i) {
        if (!used[i]) continue;
        particle[i] = static_cast<std::int64_t>(m.x.size());
        m.x.push_back(pre.x[i]);
        m.y.push_back(pre.y[i]);
        m.z.push_back(pre.z[i]);
    }
    m.particle_of_vertex.resize(nv);
    for (std::size_t i = 0; i < nv; ++i) {
        m.particle_of_vertex[i] = particle[weld[i]];
        if (weld[i] == i && !used[i]) ++m.unused;
    }
    m.triangles.reserve(kept.size());
    for (std::uint32_t v : kept) m.triangles.push_back(static_cast<std::uint32_t>(particle[v]));
    return m;
}

TriangleMesh load_obj_mesh(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0)
        throw InvalidInput(path + ": cannot open the OBJ file (" + std::strerror(errno) + ")");
    if (!S_ISREG(st.st_mode)) throw InvalidInput(path + ": is not a regular file");
    if (static_cast<std::uint64_t>(st.st_size) > mesh_max_file_bytes)
        throw InvalidInput(path + ": the OBJ file is larger than 1 GiB");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InvalidInput(path + ": cannot open the OBJ file");
    std::string text(static_cast<std::size_t>(st.st_size), '\0');
    in.read(text.data(), static_cast<std::streamsize>(text.size()));
    if (in.gcount() != static_cast<std::streamsize>(text.size()))
        throw InvalidInput(path + ": cannot read the OBJ file");
    return parse_obj_mesh(text, path);
}

void add_mesh_panel(GarmentAssembly& io, const TriangleMesh& mesh, const MeshPlacement& place) {
    const std::size_t n = mesh.particle_count();
    if (io.particle_count() + n > mesh_max_vertices)
        throw InvalidInput("mesh cloth would have " + std::to_string(io.particle_count() + n) +
                           " particles (at most 16,777,216)");
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = 0; i < n; ++i) {
        const double p[3] = {mesh.x[i], mesh.y[i], mesh.z[i]};
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
    const double mid[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const auto first = static_cast<std::uint32_t>(io.particle_count());
    for (std::size_t i = 0; i < n; ++i) {
        io.x.push_back(static_cast<float>(place.centre[0] + place.scale * (mesh.x[i] - mid[0])));
        io.y.push_back(static_cast<float>(place.centre[1] + place.scale * (mesh.y[i] - mid[1])));
        io.z.push_back(static_cast<float>(place.centre[2] + place.scale * (mesh.z[i] - mid[2])));
        io.mass.push_back(0.0f);
    }
    // Lumped masses from the placed (float) positions, in double.
    std::vector<double> lumped(n, 0.0);
    const std::size_t first_triangle = io.triangle_count();
    for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
        const std::uint32_t a = first + mesh.triangles[t], b = first + mesh.triangles[t + 1],
                            c = first + mesh.triangles[t + 2];
        const double ux = double{io.x[b]} - io.x[a], uy = double{io.y[b]} - io.y[a], uz = double{io.z[b]} - io.z[a];
        const double vx = double{io.x[c]} - io.x[a], vy = double{io.y[c]} - io.y[a], vz = double{io.z[c]} - io.z[a];
        const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
        const double area = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
        if (!(area > 0.0))
            throw InvalidInput("mesh triangle " + std::to_string(t / 3) + " has zero area after scaling by " +
                               std::to_string(place.scale) + " (float positions coincide); use a larger scale");
        for (std::uint32_t v : {a, b, c}) lumped[v - first] += area / 3.0;
        io.triangles.insert(io.triangles.end(), {a, b, c});
    }
    for (std::size_t i = 0; i < n; ++i) io.mass[first + i] = static_cast<float>(lumped[i] * place.areal_density);
    add_triangle_springs(io, std::span<const std::uint32_t>(io.triangles).subspan(first_triangle * 3));
}

std::vector<std::uint32_t> mesh_top_particles(const TriangleMesh& mesh) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = 0; i < mesh.particle_count(); ++i) {
        const double p[3] = {mesh.x[i], mesh.y[i], mesh.z[i]};
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
    double diag2 = 0.0;
    for (int k = 0; k < 3; ++k) diag2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    const double tolerance = std::max(1e-6, 1e-3 * std::sqrt(diag2));
    std::vector<std::uint32_t> out;
    for (std::size_t i = 0; i < mesh.particle_count(); ++i)
        if (mesh.y[i] >= hi[1] - tolerance) out.push_back(static_cast<std::uint32_t>(i));
    return out;
}

} // namespace drape
