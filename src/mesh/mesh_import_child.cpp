// esf_mesh_import: imports one mesh file with Assimp for load_mesh() and writes it to stdout
// (protocol: mesh_import.hpp). Started by load_mesh() with posix_spawn; a crash, a hang or an
// allocation past its limits ends this process only.

#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <stdexcept>
#include <string>

#include "core/child_process.hpp"
#include "esf/core/error.hpp"
#include "mesh/mesh_import.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define ESF_MESH_IMPORT_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ESF_MESH_IMPORT_ASAN 1
#endif
#endif

namespace {

void put(std::string& out, const void* data, std::size_t size) {
    out.append(static_cast<const char*>(data), size);
}

std::string header(std::uint64_t status, std::uint64_t a, std::uint64_t b) {
    std::string out;
    for (const std::uint64_t value : {status, a, b}) put(out, &value, sizeof value);
    return out;
}

std::string mesh_reply(const esf::Mesh& mesh) {
    std::string out =
        header(esf::detail::kMeshReplyOk, mesh.vertices.size(), mesh.triangles.size());
    out.reserve(out.size() + 12 * (mesh.vertices.size() + mesh.triangles.size()));
    for (const Eigen::Vector3f& v : mesh.vertices) {
        const float xyz[3] = {v.x(), v.y(), v.z()};
        put(out, xyz, sizeof xyz);
    }
    for (const Eigen::Vector3i& t : mesh.triangles) {
        const std::int32_t abc[3] = {t[0], t[1], t[2]};
        put(out, abc, sizeof abc);
    }
    return out;
}

std::string error_reply(std::uint64_t status, const std::string& message) {
    return header(status, message.size(), 0) + message;
}

// An allocation past the address-space limit ends the process with its own status, wherever it
// happens (Assimp turns std::bad_alloc into an error text).
[[noreturn]] void out_of_memory() { std::_Exit(esf::detail::kMeshImportOutOfMemory); }

bool parse_number(const char* text, double& value) {
    char* end = nullptr;
    value = std::strtod(text, &end);
    return end != text && *end == '\0' && std::isfinite(value) && value > 0.0;
}

// Limits this process: address space (MiB) and CPU time (seconds, rounded up, plus one).
void limit_self(double address_space_mib, double seconds) {
#if !defined(ESF_MESH_IMPORT_ASAN)
    if (address_space_mib < 1048576.0) {  // below 1 TiB; more is no limit
        const auto bytes = static_cast<rlim_t>(address_space_mib * 1048576.0);
        const rlimit space{bytes, bytes};
        ::setrlimit(RLIMIT_AS, &space);
    }
#else
    (void)address_space_mib;  // AddressSanitizer reserves terabytes of address space
#endif
    if (seconds < 1e9) {
        const auto cpu = static_cast<rlim_t>(std::ceil(seconds)) + 1;
        const rlimit time{cpu, cpu + 1};
        ::setrlimit(RLIMIT_CPU, &time);
    }
}

}  // namespace

int main(int argc, char** argv) {
    double address_space_mib = 0.0;
    double seconds = 0.0;
    if (argc != 4 || !parse_number(argv[1], address_space_mib) || !parse_number(argv[2], seconds) ||
        *argv[3] == '\0')
        return esf::detail::kMeshImportUsage;
    limit_self(address_space_mib, seconds);
    std::set_new_handler(out_of_memory);
    const std::string path = argv[3];
    std::string reply;
    try {
        reply = mesh_reply(esf::detail::import_mesh(path));
    } catch (const std::bad_alloc&) {
        out_of_memory();
    } catch (const esf::IoError& e) {
        reply = error_reply(esf::detail::kMeshReplyIoError, e.what());
    } catch (const std::invalid_argument& e) {
        reply = error_reply(esf::detail::kMeshReplyInvalidArgument, e.what());
    } catch (const std::exception& e) {
        reply =
            error_reply(esf::detail::kMeshReplyIoError,
                        esf::file_message(path, 0, std::string("cannot read mesh: ") + e.what()));
    }
    return esf::detail::write_reply(reply) ? 0 : esf::detail::kMeshImportWriteFailed;
}
