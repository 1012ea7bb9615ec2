// load_mesh(): imports a mesh file in the helper esf_mesh_import (mesh_import.hpp) and checks its
// reply. This process never runs Assimp.

#include <unistd.h>

#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/child_process.hpp"
#include "core/installed_files.hpp"
#include "core/number_text.hpp"
#include "esf/core/error.hpp"
#include "esf/mesh/mesh.hpp"
#include "mesh/mesh_checks.hpp"
#include "mesh/mesh_import.hpp"

#ifndef ESF_MESH_IMPORTER_BUILD_PATH
#define ESF_MESH_IMPORTER_BUILD_PATH ""
#endif
#ifndef ESF_MESH_IMPORTER_INSTALL_PATH
#define ESF_MESH_IMPORTER_INSTALL_PATH ""
#endif

namespace esf {
namespace {

struct FoundHelper {
    std::string path;    ///< empty: none found
    std::string looked;  ///< the places tried, for the message
};

FoundHelper find_helper() {
    FoundHelper found;
    for (const std::string& candidate : detail::installed_file_candidates(
             "ESF_MESH_IMPORTER", detail::kMeshImporterFile, ESF_MESH_IMPORTER_BUILD_PATH,
             ESF_MESH_IMPORTER_INSTALL_PATH)) {
        std::error_code error;
        if (std::filesystem::is_regular_file(candidate, error) &&
            ::access(candidate.c_str(), X_OK) == 0) {
            found.path = candidate;
            return found;
        }
        found.looked += (found.looked.empty() ? "" : ", ") + candidate;
    }
    if (found.looked.empty()) found.looked = "no place to look";
    return found;
}

/// The helper: searched once per process, unless ESF_MESH_IMPORTER names it (then each time).
FoundHelper helper() {
    if (const char* chosen = std::getenv("ESF_MESH_IMPORTER"); chosen != nullptr && *chosen)
        return find_helper();
    static const FoundHelper found = find_helper();  // thread-safe, once
    return found;
}

std::string number(double value) { return detail::significant_text(value, 6); }

/// The mesh in a status-0 reply; throws IoError for one that is cut short, too long or names a
/// vertex that is not there.
Mesh decode_mesh(const std::string& path, const char* payload, std::size_t size,
                 std::uint64_t vertices, std::uint64_t triangles) {
    const auto malformed = [&](const std::string& why) {
        return IoError(
            file_message(path, 0, "the mesh importer's reply is malformed (" + why + ")"));
    };
    constexpr std::uint64_t kItem = 3 * 4;
    if (vertices > size / kItem || triangles > size / kItem ||
        (vertices + triangles) * kItem != size)
        throw malformed(std::to_string(vertices) + " vertices and " + std::to_string(triangles) +
                        " triangles in " + std::to_string(size) + " bytes");
    if (vertices > static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
        throw malformed("too many vertices");
    Mesh mesh;
    mesh.vertices.resize(vertices);
    mesh.triangles.resize(triangles);
    for (std::size_t i = 0; i < vertices; ++i) {
        float xyz[3];
        std::memcpy(xyz, payload + i * kItem, sizeof xyz);
        mesh.vertices[i] = Eigen::Vector3f(xyz[0], xyz[1], xyz[2]);
    }
    payload += vertices * kItem;
    const auto count = static_cast<std::int64_t>(vertices);
    for (std::size_t i = 0; i < triangles; ++i) {
        std::int32_t abc[3];
        std::memcpy(abc, payload + i * kItem, sizeof abc);
        for (const std::int32_t index : abc)
            if (index < 0 || index >= count)
                throw malformed("triangle " + std::to_string(i) + " names vertex " +
                                std::to_string(index));
        mesh.triangles[i] = Eigen::Vector3i(abc[0], abc[1], abc[2]);
    }
    return mesh;
}

}  // namespace

Mesh load_mesh(const std::string& path) { return load_mesh(path, MeshImportLimits{}); }

Mesh load_mesh(const std::string& path, const MeshImportLimits& limits) {
    // Missing files, folders and FIFOs are refused here: the helper never waits on one.
    detail::mesh_file_size(path);
    const FoundHelper found = helper();
    if (found.path.empty())
        throw IoError(file_message(path, 0,
                                   std::string("cannot import meshes: its helper ") +
                                       detail::kMeshImporterFile + " is missing (looked in " +
                                       found.looked + ")"));
    if (!(limits.address_space_mib > 0) || !(limits.seconds > 0.0))
        throw std::invalid_argument("load_mesh: the import limits must be positive");

    detail::ChildLimits child;
    child.seconds = limits.seconds;
    // The reply holds at most what the helper's address space does (and a header).
    child.max_reply_bytes =
        limits.address_space_mib >= (std::numeric_limits<std::size_t>::max() >> 21)
            ? std::numeric_limits<std::size_t>::max()
            : (limits.address_space_mib << 20) + 1024;
    detail::ChildResult result;
    try {
        result = detail::run_child(
            found.path, {std::to_string(limits.address_space_mib), number(limits.seconds), path},
            "", child);
    } catch (const std::runtime_error& e) {
        throw IoError(file_message(path, 0, e.what()));
    }

    const auto importer = [&](const std::string& what) {
        return IoError(file_message(path, 0, "the mesh importer " + what));
    };
    using End = detail::ChildResult::End;
    if (result.end == End::kTimedOut || (result.end == End::kSignalled && result.code == SIGXCPU))
        throw importer("took longer than " + number(limits.seconds) + " s");
    if (result.end == End::kReplyTooLarge)
        throw importer("wrote a reply larger than " + std::to_string(limits.address_space_mib) +
                       " MiB");
    if (result.end == End::kSignalled)
        throw importer("crashed (signal " + std::to_string(result.code) + ")");
    if (result.code == detail::kMeshImportOutOfMemory)
        throw importer("needed more than " + std::to_string(limits.address_space_mib) + " MiB");
    if (result.code != 0) throw importer("failed (" + detail::describe_end(result) + ")");

    std::uint64_t header[3];
    const std::string& reply = result.reply;
    if (reply.size() < sizeof header)
        throw IoError(file_message(
            path, 0,
            "the mesh importer's reply is malformed (" + std::to_string(reply.size()) + " bytes)"));
    std::memcpy(header, reply.data(), sizeof header);
    const char* payload = reply.data() + sizeof header;
    const std::size_t size = reply.size() - sizeof header;
    if (header[0] == detail::kMeshReplyOk)
        return decode_mesh(path, payload, size, header[1], header[2]);
    if ((header[0] != detail::kMeshReplyIoError &&
         header[0] != detail::kMeshReplyInvalidArgument) ||
        header[1] != size || header[2] != 0)
        throw IoError(file_message(
            path, 0,
            "the mesh importer's reply is malformed (status " + std::to_string(header[0]) + ")"));
    const std::string message(payload, size);
    if (header[0] == detail::kMeshReplyInvalidArgument) throw std::invalid_argument(message);
    throw IoError(message);
}

}  // namespace esf
