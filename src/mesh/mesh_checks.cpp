// The checks load_mesh() runs on a mesh file before Assimp reads it (mesh_checks.hpp).

#include "mesh/mesh_checks.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "esf/core/error.hpp"
#include "io/ply_header.hpp"

namespace esf::detail {
namespace {

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
// header announces; check the header (io/ply_header.hpp) against the file size first.
void check_ply_header(const std::string& path, std::uintmax_t file_size) {
    constexpr std::size_t kMaxHeader = std::size_t{1} << 20;
    std::ifstream in(path, std::ios::binary);
    std::string start(static_cast<std::size_t>(std::min<std::uintmax_t>(file_size, kMaxHeader)),
                      '\0');
    in.read(start.data(), static_cast<std::streamsize>(start.size()));
    start.resize(static_cast<std::size_t>(in.gcount()));
    const PlyHeader header = read_ply_header(start);
    if (!header.is_ply) return;  // not PLY: Assimp reports it
    const bool ended = header.ended;
    const bool binary = header.format != PlyFormat::kAscii;
    const bool big_endian = header.format == PlyFormat::kBinaryBig;
    // A header cut before its last newline counts that newline too (nothing follows it).
    const bool last_line_open =
        header.data_pos == start.size() && (start.empty() || start.back() != '\n');
    const std::size_t header_bytes = header.data_pos + (last_line_open ? 1 : 0);
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
    for (const PlyElement& ply : header.elements) {
        Element e;
        e.name = ply.name;
        e.count = ply.written_count;
        if (!(e.count >= 0)) known_sizes = false;
        for (const PlyProperty& p : ply.properties) {
            if (!p.known_type) known_sizes = false;
            Property property;
            property.size = static_cast<int>(scalar_size(p.type));
            if (p.is_list) property.count_size = static_cast<int>(scalar_size(p.count_type));
            e.min_bytes += property.count_size ? property.count_size : property.size;
            ++e.properties;
            e.layout.push_back(property);
        }
        elements.push_back(std::move(e));
    }
    if (!ended) throw IoError(file_message(path, 0, "PLY header has no end_header line"));
    // Assimp 5.2 takes a line feed right after end_header for part of the header and reads every
    // binary value one byte late (a mesh of garbage, or indices out of range).
    if (binary && header.data_pos < start.size() && start[header.data_pos] == '\n')
        throw IoError(file_message(
            path, 0,
            "binary PLY data starting with a line feed byte (0x0A), which the importer misreads "
            "as the end of the header; write the mesh again (esf writes it another way) or as "
            "ASCII PLY"));
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
    in.clear();
    in.seekg(static_cast<std::streamoff>(std::min<std::uintmax_t>(header_bytes, file_size)));
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

}  // namespace

std::uintmax_t mesh_file_size(const std::string& path) {
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
    return file_size;
}

void check_mesh_file(const std::string& path, std::uintmax_t file_size) {
    check_ply_header(path, file_size);
    check_off(path, file_size);
    check_stl(path, file_size);
}

}  // namespace esf::detail
