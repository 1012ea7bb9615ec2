#include "esf/mesh.hpp"

#include <assimp/DefaultIOSystem.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "esf/error.hpp"
#include "mesh_checks.hpp"

namespace esf {
namespace {

Eigen::Matrix4d to_eigen(const aiMatrix4x4& m) {
    Eigen::Matrix4d out;
    out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3,
        m.d4;
    return out;
}

// Appends the triangles of one mesh, its vertices mapped by `transform`.
void append(const aiMesh& mesh, const Eigen::Matrix4d& transform, Mesh& out) {
    const auto base = static_cast<int>(out.vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
        const aiVector3D& p = mesh.mVertices[v];
        const Eigen::Vector4d q = transform * Eigen::Vector4d(p.x, p.y, p.z, 1.0);
        out.vertices.push_back((q.head<3>() / q.w()).cast<float>());
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
        const aiFace& face = mesh.mFaces[f];
        if (face.mNumIndices != 3) continue;  // points and lines
        const Eigen::Vector3i t(static_cast<int>(face.mIndices[0]),
                                static_cast<int>(face.mIndices[1]),
                                static_cast<int>(face.mIndices[2]));
        if (t.minCoeff() < 0 || t.maxCoeff() >= static_cast<int>(mesh.mNumVertices)) continue;
        out.triangles.emplace_back(t.array() + base);
    }
}

// Appends every mesh under `node`, transformed to the root frame.
void collect(const aiScene& scene, const aiNode& node, const Eigen::Matrix4d& parent,
             std::vector<bool>& used, Mesh& out) {
    const Eigen::Matrix4d transform = parent * to_eigen(node.mTransformation);
    for (unsigned k = 0; k < node.mNumMeshes; ++k) {
        const unsigned mesh_index = node.mMeshes[k];
        if (mesh_index >= scene.mNumMeshes || scene.mMeshes[mesh_index] == nullptr) continue;
        used[mesh_index] = true;
        append(*scene.mMeshes[mesh_index], transform, out);
    }
    for (unsigned c = 0; c < node.mNumChildren; ++c) {
        if (node.mChildren[c] != nullptr) collect(scene, *node.mChildren[c], transform, used, out);
    }
}

// Drops triangles with a repeated vertex index and vertices no triangle uses.
Mesh compact(const Mesh& mesh) {
    Mesh out;
    std::vector<int> remap(mesh.vertices.size(), -1);
    out.triangles.reserve(mesh.triangles.size());
    for (const Eigen::Vector3i& t : mesh.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        Eigen::Vector3i r;
        for (int k = 0; k < 3; ++k) {
            int& index = remap[static_cast<std::size_t>(t[k])];
            if (index < 0) {
                index = static_cast<int>(out.vertices.size());
                out.vertices.push_back(mesh.vertices[static_cast<std::size_t>(t[k])]);
            }
            r[k] = index;
        }
        out.triangles.push_back(r);
    }
    return out;
}

// The list lengths of a PLY body against the bytes that hold them (Assimp allocates whatever a
// list announces): `in` stands after end_header; `remaining` bytes follow it. ASCII elements are
// one line each.
template <class Element>
void check_ply_lists(std::istream& in, const std::string& path,
                     const std::vector<Element>& elements, bool binary, bool big_endian,
                     std::uint64_t remaining) {
    const auto fail = [&](const Element& e, std::uint64_t i, const std::string& reason) {
        throw IoError(file_message(
            path, 0, "PLY " + e.name + " element " + std::to_string(i) + ": " + reason));
    };
    bool has_list = false;
    for (const Element& e : elements)
        for (const auto& p : e.layout) has_list = has_list || p.count_size != 0;
    if (!has_list) return;  // the counts were checked against the file size
    std::string line;
    for (const Element& e : elements) {
        // Counts beyond 2^64 are as good as endless: the bytes or lines run out first.
        const std::uint64_t count = e.count < 0x1p64 ? static_cast<std::uint64_t>(e.count)
                                                     : std::numeric_limits<std::uint64_t>::max();
        if (binary && std::none_of(e.layout.begin(), e.layout.end(),
                                   [](const auto& p) { return p.count_size != 0; })) {
            // Fixed-size elements (none, when the element has no property) are skipped whole:
            // their bytes were checked against the file size.
            const auto bytes = static_cast<std::uint64_t>(e.min_bytes) * count;
            if (e.min_bytes > 0 && bytes > remaining)
                fail(e, 0, "truncated (the elements need more bytes than are left)");
            if (e.min_bytes > 0) {
                in.ignore(static_cast<std::streamsize>(bytes));
                remaining -= bytes;
            }
            continue;
        }
        for (std::uint64_t i = 0; i < count; ++i) {
            if (binary) {
                for (const auto& p : e.layout) {
                    std::uint64_t items = 1;
                    if (p.count_size != 0) {
                        unsigned char bytes[8] = {};
                        const auto n = static_cast<std::size_t>(p.count_size);
                        if (remaining < n || !in.read(reinterpret_cast<char*>(bytes),
                                                      static_cast<std::streamsize>(n)))
                            fail(e, i, "truncated (a list count is missing)");
                        remaining -= n;
                        items = 0;
                        for (std::size_t b = 0; b < n; ++b)
                            items |= std::uint64_t{bytes[big_endian ? n - 1 - b : b]} << (8 * b);
                        // The count types of real files are unsigned char and int; a negative
                        // int reads as a huge count and is refused below.
                    }
                    const std::uint64_t bytes = items * static_cast<std::uint64_t>(p.size);
                    if (items > remaining || bytes > remaining)
                        fail(e, i,
                             "a list of " + std::to_string(items) + " items, more than the " +
                                 std::to_string(remaining) + " bytes left in the file hold");
                    in.ignore(static_cast<std::streamsize>(bytes));
                    remaining -= bytes;
                }
                continue;
            }
            do {
                if (!std::getline(in, line)) fail(e, i, "truncated (the line is missing)");
            } while (line.find_first_not_of(" \t\r") == std::string::npos);
            std::istringstream values(line);
            std::string value;
            for (const auto& p : e.layout) {
                if (!(values >> value)) fail(e, i, "fewer values than the element's properties");
                if (p.count_size == 0) continue;
                char* end = nullptr;
                const double items = std::strtod(value.c_str(), &end);
                if (*end != '\0' || !(items >= 0.0) || items != std::floor(items))
                    fail(e, i, "a list count that is not a whole number >= 0");
                // Each item takes at least a digit and a separator of this line.
                if (items * 2.0 > static_cast<double>(line.size())) {
                    std::ostringstream reason;
                    reason << "a list of " << items << " items on a line of " << line.size()
                           << " characters";
                    fail(e, i, reason.str());
                }
                for (double k = 0; k < items; ++k)
                    if (!(values >> value)) fail(e, i, "a list shorter than its count");
            }
        }
    }
}

// Assimp 5.2 loops forever on a PLY header without `end_header` and allocates whatever the
// header announces; check the header against the file size first.
void check_ply_header(const std::string& path, std::uintmax_t file_size) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    if (!std::getline(in, line)) return;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line != "ply" && line != "PLY") return;  // not PLY: Assimp reports it

    constexpr std::size_t kMaxHeader = std::size_t{1} << 20;
    std::size_t header_bytes = line.size() + 1;
    bool binary = false;
    bool big_endian = false;
    bool known_sizes = true;
    struct Property {
        int size = 0;        // bytes of a value (of an item, for a list)
        int count_size = 0;  // bytes of a list's count; 0: not a list
    };
    struct Element {
        std::string name;
        double count = 0;
        double min_bytes = 0;  // per element: fixed properties and list counts
        int properties = 0;
        std::vector<Property> layout;
    };
    std::vector<Element> elements;
    const auto type_size = [](const std::string& type) -> int {
        if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
        if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
        if (type == "int" || type == "uint" || type == "int32" || type == "uint32" ||
            type == "float" || type == "float32")
            return 4;
        if (type == "double" || type == "float64") return 8;
        return 0;
    };
    bool ended = false;
    while (header_bytes < kMaxHeader && std::getline(in, line)) {
        header_bytes += line.size() + 1;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        if (keyword == "end_header") {
            ended = true;
            break;
        }
        if (keyword == "format") {
            std::string format;
            words >> format;
            binary = format.rfind("binary", 0) == 0;
            big_endian = format == "binary_big_endian";
        } else if (keyword == "element") {
            Element e;
            words >> e.name >> e.count;
            if (!words || !(e.count >= 0)) known_sizes = false;
            elements.push_back(e);
        } else if (keyword == "property" && !elements.empty()) {
            std::string type;
            words >> type;
            Property property;
            if (type == "list") {  // the count type; items may be none
                std::string item;
                words >> type >> item;
                property.count_size = type_size(type);
                property.size = type_size(item);
                if (property.size == 0) known_sizes = false;
            } else {
                property.size = type_size(type);
            }
            const int size = property.count_size ? property.count_size : property.size;
            if (size == 0) known_sizes = false;
            elements.back().min_bytes += size;
            ++elements.back().properties;
            elements.back().layout.push_back(property);
        }
    }
    if (!ended) throw IoError(file_message(path, 0, "PLY header has no end_header line"));
    if (!known_sizes) return;
    const double available = static_cast<double>(file_size) - static_cast<double>(header_bytes);
    double need = 0.0;
    for (const Element& e : elements) {
        // ASCII needs at least one digit and a separator per property. An element without
        // properties counts as a byte: Assimp keeps a record of every one it reads.
        need += e.count * std::max(1.0, binary ? e.min_bytes : 2.0 * e.properties);
        if (need > available) {
            std::ostringstream reason;
            reason << "truncated PLY: the header announces " << e.count << " " << e.name
                   << " elements, needing at least " << need
                   << " bytes with those before them, but " << available
                   << " bytes follow the header";
            throw IoError(file_message(path, 0, reason.str()));
        }
    }
    // A header cut before its last newline leaves `available` at -1: nothing follows it.
    check_ply_lists(in, path, elements, binary, big_endian,
                    static_cast<std::uint64_t>(std::max(0.0, available)));
}

// Assimp 5.2 allocates whatever an OFF header announces and clamps a face's out-of-range vertex
// index to the last vertex. OFF is text: check the counts against the file size, then that the
// file holds that many vertices and faces and that every index names a vertex.
void check_off(const std::string& path, std::uintmax_t file_size) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    std::size_t line_number = 0;
    const auto next = [&]() -> bool {  // the next line with content, comments removed
        while (std::getline(in, line)) {
            ++line_number;
            if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
            if (line.find_first_not_of(" \t\r") != std::string::npos) return true;
        }
        return false;
    };
    const auto fail = [&](std::size_t at, const std::string& reason) {
        throw IoError(file_message(path, at, reason));
    };
    if (!next()) return;
    std::istringstream first(line);
    std::string magic;
    first >> magic;
    // [ST][C][N][4][n]OFF; 4-D, n-D and binary variants are left to Assimp.
    if (magic.size() < 3 || magic.compare(magic.size() - 3, 3, "OFF") != 0) return;
    if (magic.find_first_of("4n") != std::string::npos) return;
    std::string rest;
    std::getline(first, rest);
    if (rest.find("BINARY") != std::string::npos) return;
    if (rest.find_first_not_of(" \t\r") == std::string::npos) {
        if (!next()) fail(0, "OFF file ends before its vertex and face counts");
        rest = line;
    }
    const std::size_t counts_line = line_number;
    std::istringstream counts(rest);
    double vertices = -1.0, faces = -1.0;
    counts >> vertices >> faces;
    if (!counts || !(vertices >= 0.0) || !(faces >= 0.0) || vertices != std::floor(vertices) ||
        faces != std::floor(faces))
        fail(counts_line, "OFF vertex and face counts are not two whole numbers >= 0");
    // At least "x y z" and a line end per vertex, "n" and a line end per face.
    const double need = 6.0 * vertices + 2.0 * faces;
    if (need > static_cast<double>(file_size)) {
        std::ostringstream reason;
        reason << "truncated OFF: the header announces " << vertices << " vertices and " << faces
               << " faces, needing at least " << need << " bytes, but the file has " << file_size;
        fail(counts_line, reason.str());
    }
    const auto vertex_count = static_cast<std::size_t>(vertices);
    const auto face_count = static_cast<std::size_t>(faces);
    for (std::size_t v = 0; v < vertex_count; ++v)
        if (!next())
            fail(0, "truncated OFF: " + std::to_string(v) + " of the " +
                        std::to_string(vertex_count) + " vertices the header announces");
    for (std::size_t f = 0; f < face_count; ++f) {
        if (!next())
            fail(0, "truncated OFF: " + std::to_string(f) + " of the " +
                        std::to_string(face_count) + " faces the header announces");
        std::istringstream face(line);
        long long n = -1;
        face >> n;
        if (!face || n < 0)
            fail(line_number, "OFF face " + std::to_string(f) + " has no valid vertex count");
        for (long long i = 0; i < n; ++i) {
            long long index = -1;
            if (!(face >> index))
                fail(line_number, "OFF face " + std::to_string(f) + " lists fewer than " +
                                      std::to_string(n) + " vertex indices");
            if (index < 0 || static_cast<std::size_t>(index) >= vertex_count)
                fail(line_number, "OFF face " + std::to_string(f) + " has vertex index " +
                                      std::to_string(index) + " outside [0, " +
                                      std::to_string(vertex_count) + ")");
        }
    }
}

// A binary STL is an 80-byte header, a little-endian uint32 triangle count and 50 bytes a
// triangle. Assimp 5.2 takes a file for one when 84 + 50 x count, computed in 32 bits, equals the
// file size, so a count that wraps around (2^31 + 1 in a 134-byte file) is read as binary STL;
// only its own later check, in 64 bits, stops it short of allocating 3 x count corners. The count
// is checked here, in 64 bits, before Assimp sees the file, for files Assimp may read as STL
// (named .stl, or with "stl" or "solid" in their first 200 bytes, as Assimp's own test): a count
// matching only in 32 bits is an error, as is any mismatch in a .stl file that is not ASCII (ASCII
// STL starts with "solid" and has no count).
void check_stl(const std::string& path, std::uintmax_t file_size) {
    constexpr std::size_t kHeader = 84;
    if (file_size < kHeader) return;  // not binary STL for Assimp either
    std::ifstream in(path, std::ios::binary);
    char bytes[200] = {};
    in.read(bytes, sizeof bytes);
    const auto got = static_cast<std::size_t>(in.gcount());
    if (got < kHeader) return;
    std::string head;  // lower case, NUL bytes dropped (Assimp's signature test does the same)
    for (std::size_t i = 0; i < got; ++i)
        if (bytes[i] != '\0')
            head.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(bytes[i]))));
    std::string extension = std::filesystem::path(path).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const bool named_stl = extension == ".stl";
    if (!named_stl && head.find("stl") == std::string::npos &&
        head.find("solid") == std::string::npos)
        return;
    std::uint32_t count = 0;
    for (std::size_t b = 0; b < 4; ++b)
        count |= std::uint32_t{static_cast<unsigned char>(bytes[80 + b])} << (8 * b);
    const std::uint64_t need = kHeader + 50 * std::uint64_t{count};
    if (need == file_size) return;
    const bool wraps = static_cast<std::uint32_t>(need) == static_cast<std::uint32_t>(file_size);
    const std::size_t text = std::string_view(bytes, got).find_first_not_of(" \t\r\n");
    const bool ascii =
        text != std::string_view::npos && std::string_view(bytes, got).substr(text, 5) == "solid";
    if (wraps || (named_stl && !ascii))
        throw IoError(file_message(path, 0,
                                   "truncated binary STL: the header announces " +
                                       std::to_string(count) + " triangles, needing " +
                                       std::to_string(need) + " bytes, but the file has " +
                                       std::to_string(file_size)));
}

/// Assimp's file access for one model: regular files in the model's folder or below it (the
/// folder as named, with its links resolved, or the one a symbolic link to the model leads to).
/// Anything else (a material library or glTF buffer outside the folder, a FIFO, a device) does not
/// exist for Assimp, so it is neither opened nor quoted in a message.
class FolderIOSystem : public Assimp::DefaultIOSystem {
  public:
    explicit FolderIOSystem(const std::string& model) {
        namespace fs = std::filesystem;
        std::error_code ec;
        const fs::path given = fs::absolute(fs::path(model), ec).lexically_normal();
        folders_.push_back(given.parent_path());
        const fs::path folder = fs::canonical(given.parent_path(), ec);
        if (!ec) folders_.push_back(folder);
        const fs::path real = fs::canonical(given, ec);
        if (!ec) folders_.push_back(real.parent_path());
    }
    bool Exists(const char* file) const override {
        return allowed(file) && Assimp::DefaultIOSystem::Exists(file);
    }
    Assimp::IOStream* Open(const char* file, const char* mode) override {
        if (mode == nullptr || std::string(mode).find_first_of("wa+") != std::string::npos ||
            !allowed(file))
            return nullptr;
        return Assimp::DefaultIOSystem::Open(file, mode);
    }

  private:
    bool allowed(const char* file) const {
        namespace fs = std::filesystem;
        if (file == nullptr) return false;
        std::error_code ec;
        const fs::path real = fs::canonical(fs::path(file), ec);
        if (ec) return false;
        struct stat st {};
        if (::stat(real.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
        const auto inside = [&real](const fs::path& folder) {
            return std::mismatch(folder.begin(), folder.end(), real.begin(), real.end()).first ==
                   folder.end();
        };
        return std::any_of(folders_.begin(), folders_.end(), inside);
    }

    std::vector<std::filesystem::path> folders_;
};

}  // namespace

void detail::check_mesh_file(const std::string& path, std::uintmax_t file_size) {
    check_ply_header(path, file_size);
    check_off(path, file_size);
    check_stl(path, file_size);
}

Eigen::Vector3f Mesh::min_corner() const {
    if (vertices.empty()) throw std::invalid_argument("min_corner: mesh has no vertex");
    Eigen::Vector3f m = vertices.front();
    for (const auto& v : vertices) m = m.cwiseMin(v);
    return m;
}

Eigen::Vector3f Mesh::max_corner() const {
    if (vertices.empty()) throw std::invalid_argument("max_corner: mesh has no vertex");
    Eigen::Vector3f m = vertices.front();
    for (const auto& v : vertices) m = m.cwiseMax(v);
    return m;
}

double Mesh::bounding_radius() const {
    const Eigen::Vector3d centre =
        (min_corner().cast<double>() + max_corner().cast<double>()) / 2.0;
    double radius = 0.0;
    for (const auto& v : vertices) radius = std::max(radius, (v.cast<double>() - centre).norm());
    return radius;
}

void check_mesh(const Mesh& mesh, const std::string& what) {
    if (mesh.triangles.empty()) throw std::invalid_argument(what + ": mesh has no triangle");
    if (mesh.vertices.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
        throw std::invalid_argument(what + ": too many vertices");
    const int n = static_cast<int>(mesh.vertices.size());
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        const Eigen::Vector3i& t = mesh.triangles[i];
        if (t.minCoeff() < 0 || t.maxCoeff() >= n)
            throw std::invalid_argument(what + ": triangle " + std::to_string(i) +
                                        " has a vertex index outside [0, " + std::to_string(n) +
                                        ")");
    }
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        if (!mesh.vertices[i].allFinite())
            throw std::invalid_argument(what + ": vertex " + std::to_string(i) + " is not finite");
    }
}

Mesh load_mesh(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw IoError(file_message(path, 0, ec ? "cannot read: " + ec.message() : "no such file"));
    if (std::filesystem::is_directory(path, ec))
        throw IoError(file_message(path, 0, "is a directory, not a mesh file"));
    const std::uintmax_t file_size = std::filesystem::file_size(path, ec);
    if (ec) throw IoError(file_message(path, 0, "cannot read: " + ec.message()));
    if (file_size == 0) throw IoError(file_message(path, 0, "empty file"));
    if (!std::filesystem::is_regular_file(path, ec))
        throw IoError(file_message(path, 0, "not a regular file"));
    detail::check_mesh_file(path, file_size);

    Assimp::Importer importer;
    importer.SetIOHandler(new FolderIOSystem(path));  // the importer owns and deletes it
    const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
    const auto fail = [&] {
        std::string reason = importer.GetErrorString();
        if (reason.empty()) reason = "unknown error";
        return IoError(file_message(path, 0, "cannot read mesh: " + reason));
    };
    if (scene == nullptr) throw fail();
    // Checked before post-processing: JoinIdenticalVertices merges NaN vertices with others.
    for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
        const aiMesh* mesh = scene->mMeshes[i];
        for (unsigned v = 0; mesh != nullptr && v < mesh->mNumVertices; ++v) {
            const aiVector3D& p = mesh->mVertices[v];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw IoError(file_message(path, 0, "has a non-finite vertex"));
        }
    }
    // Only positions matter: dropping normals, texture coordinates and colours first lets
    // JoinIdenticalVertices merge the vertices that files split along seams.
    importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                                aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                    aiComponent_COLORS | aiComponent_TEXCOORDS |
                                    aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                    aiComponent_TEXTURES | aiComponent_LIGHTS |
                                    aiComponent_CAMERAS | aiComponent_MATERIALS);
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                                aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    scene = importer.ApplyPostProcessing(aiProcess_RemoveComponent | aiProcess_Triangulate |
                                         aiProcess_SortByPType | aiProcess_JoinIdenticalVertices);
    if (scene == nullptr) {
        // SortByPType fails when only points and lines were there.
        if (std::string(importer.GetErrorString()).find("No meshes remaining") != std::string::npos)
            throw IoError(file_message(path, 0, "holds no triangle"));
        throw fail();
    }
    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 || scene->mNumMeshes == 0)
        throw IoError(file_message(path, 0, "holds no triangle"));

    Mesh merged;
    std::vector<bool> used(scene->mNumMeshes, false);
    if (scene->mRootNode != nullptr)
        collect(*scene, *scene->mRootNode, Eigen::Matrix4d::Identity(), used, merged);
    // Meshes no node refers to (possible in some formats) are taken as they are.
    for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
        if (!used[i] && scene->mMeshes[i] != nullptr)
            append(*scene->mMeshes[i], Eigen::Matrix4d::Identity(), merged);
    }

    Mesh out = compact(merged);
    if (out.triangles.empty()) throw IoError(file_message(path, 0, "holds no triangle"));
    for (const auto& v : out.vertices) {
        if (!v.allFinite())  // finite in the file, overflowed by a node transform
            throw IoError(file_message(path, 0, "has a non-finite vertex"));
    }
    return out;
}

void write_ply_mesh(const std::string& path, const Mesh& mesh) {
    check_mesh(mesh, path);
    std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by esf\n";
    header += "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
    header += "property float x\nproperty float y\nproperty float z\n";
    header += "element face " + std::to_string(mesh.triangles.size()) + "\n";
    header += "property list uchar int vertex_indices\nend_header\n";

    std::vector<char> body;
    body.reserve(mesh.vertices.size() * 12 + mesh.triangles.size() * 13);
    const auto put = [&body](const void* data, std::size_t size) {
        const char* bytes = static_cast<const char*>(data);
        if constexpr (std::endian::native == std::endian::little) {
            body.insert(body.end(), bytes, bytes + size);
        } else {
            for (std::size_t i = size; i-- > 0;) body.push_back(bytes[i]);
        }
    };
    for (const auto& v : mesh.vertices) {
        for (int k = 0; k < 3; ++k) put(&v[k], sizeof(float));
    }
    for (const auto& t : mesh.triangles) {
        body.push_back(static_cast<char>(3));
        for (int k = 0; k < 3; ++k) {
            const std::int32_t index = t[k];
            put(&index, sizeof(index));
        }
    }

    std::string temp = path + ".XXXXXX";
    const int fd = ::mkstemp(temp.data());
    if (fd < 0)
        throw IoError(file_message(path, 0, std::string("cannot create: ") + std::strerror(errno)));
    bool ok = ::fchmod(fd, 0644) == 0;
    const auto write_all = [fd](const char* data, std::size_t size) {
        while (size > 0) {
            const ssize_t n = ::write(fd, data, size);
            if (n < 0) {
                if (errno == EINTR) continue;
                return false;
            }
            data += n;
            size -= static_cast<std::size_t>(n);
        }
        return true;
    };
    ok = ok && write_all(header.data(), header.size()) && write_all(body.data(), body.size());
    const int saved_errno = errno;
    ok = (::close(fd) == 0) && ok;
    if (!ok || std::rename(temp.c_str(), path.c_str()) != 0) {
        const int error = ok ? errno : saved_errno;
        ::unlink(temp.c_str());
        throw IoError(file_message(path, 0, std::string("cannot write: ") + std::strerror(error)));
    }
}

}  // namespace esf
