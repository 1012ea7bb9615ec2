// The mesh import itself, with Assimp (mesh_import.hpp): run by the helper esf_mesh_import only.

#include "mesh/mesh_import.hpp"

#include <assimp/DefaultIOSystem.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <sys/stat.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "esf/core/error.hpp"
#include "mesh/mesh_checks.hpp"

namespace esf::detail {
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

Mesh import_mesh(const std::string& path) {
    check_mesh_file(path, mesh_file_size(path));

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

}  // namespace esf::detail
