#pragma once
// The training database: one SQLite file holding the categories, models, rendered views (pose,
// point count), their descriptors and every setting they were made with.
//
// Layout (schema version kDatabaseSchemaVersion, SQLite application id "ESF1"):
//   settings(key, value)                       typed values: integer, real or text
//   categories(id, name)
//   models(id, category_id, name, file, grp, scale, status, error)    one row per model file
//   views(id, model_id, view_index, points, pose, skip_reason)        one row per rendered view
//   descriptor_kinds(id, name, version, dimension)                    e.g. ("esf", 1, 640)
//   descriptors(view_id, kind_id, signature, data)                    float32 blobs, several
//                                                                     signatures per view allowed
//   weights(kind_id, data)                                            learned block weights
//   weights_basis(kind_id, fingerprint)                               what they were learned on
//
// Writes go through write_model(): a model and all its views and descriptors in one transaction
// (write-ahead log while a writer is open, synced on every commit), so a killed writer leaves
// every model either complete or absent, and nothing committed is lost. A writer that closes
// cleanly leaves one self-contained file (rollback-journal mode). Thread safety: a Database is one
// SQLite connection; use it from one thread at a time. Several processes may read one file while
// one writes.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "esf/core/enum_names.hpp"
#include "esf/mesh/model_surface.hpp"

namespace esf {

/// Schema version stored in the file (PRAGMA user_version); bumped on incompatible changes.
inline constexpr int kDatabaseSchemaVersion = 1;

enum class OpenMode {
    kRead,   ///< the file must exist; never creates or modifies a file
    kWrite,  ///< creates the file (and its schema) when it does not exist
};

/// A setting value as stored: integer, real or text.
using SettingValue = std::variant<std::int64_t, double, std::string>;
using Settings = std::map<std::string, SettingValue>;

/// Text form of a setting value ("1", "0.5", "kinect"); reals round-trip exactly.
std::string to_string(const SettingValue& value);

/// A descriptor type stored in a database, e.g. {"esf", kEsfVersion, 640}.
struct DescriptorKind {
    std::string name;
    int version = 0;
    int dimension = 0;

    bool operator==(const DescriptorKind&) const = default;
};

/// One rendered view of a model.
struct ViewEntry {
    int index = 0;           ///< view sphere index
    std::size_t points = 0;  ///< points in the rendered view
    /// Model (file coordinates) -> camera; the upper-left block is scale * rotation when the
    /// model was rescaled (ModelEntry::scale).
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
    /// signatures x dimension floats, row-major (ESF: one signature of 640). Empty when skipped.
    std::vector<float> descriptors;
    /// Why the view has no descriptor (too few points, degenerate); empty when it has one.
    std::string skip_reason;

    bool skipped() const { return descriptors.empty(); }
};

enum class ModelStatus { kComplete, kFailed };

/// "complete", "failed".
template <>
struct EnumNames<ModelStatus> {
    static constexpr const char* what = "model status";
    static constexpr std::array<EnumName<ModelStatus>, 2> table{
        {{ModelStatus::kComplete, "complete"}, {ModelStatus::kFailed, "failed"}}};
};

/// A model with all its views, as written by Database::write_model().
struct ModelEntry {
    std::string category;
    std::string name;
    std::string file;    ///< source file (relative to the training root)
    std::string group;   ///< shape group for leave-one-group-out splits; empty: the model name
    double scale = 1.0;  ///< factor applied to the file's coordinates before rendering
    /// Non-empty: the model failed (e.g. its mesh did not load); no views are stored.
    std::string error;
    std::vector<ViewEntry> views;
    /// The model's surface samples (metres: the file's coordinates times `scale`), stored for
    /// verification; none for a failed model.
    std::optional<ModelSurface> surface;
};

/// A stored model and its counts.
struct ModelInfo {
    std::string category;
    std::string name;
    std::string file;
    std::string group;
    double scale = 1.0;
    ModelStatus status = ModelStatus::kComplete;
    std::string error;
    std::size_t views = 0;          ///< views with a descriptor
    std::size_t skipped_views = 0;  ///< views without one
};

struct CategoryInfo {
    std::string name;
    std::size_t models = 0;  ///< complete models
    std::size_t failed_models = 0;
    std::size_t views = 0;
    std::size_t skipped_views = 0;
};

/// Counts over the whole database.
struct DatabaseSummary {
    std::vector<CategoryInfo> categories;  ///< sorted by name
    std::size_t models = 0;                ///< complete models
    std::size_t failed_models = 0;
    std::size_t views = 0;
    std::size_t skipped_views = 0;
    std::size_t surfaces = 0;  ///< complete models with a stored surface
    std::vector<DescriptorKind> descriptor_kinds;
};

/// Metadata of one row of a DescriptorMatrix.
struct DescriptorRow {
    std::uint32_t category = 0;  ///< index into DescriptorMatrix::categories
    std::uint32_t model = 0;     ///< index into DescriptorMatrix::models
    int view_index = 0;
    int signature = 0;
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();  ///< model -> camera
};

/// All descriptors of one kind in one contiguous row-major matrix, for a k-NN index. Rows are
/// ordered by (category name, model name, view index, signature): the order does not depend on
/// the order models were trained in.
struct DescriptorMatrix {
    DescriptorKind kind;
    std::vector<float> data;              ///< rows() x kind.dimension
    std::vector<DescriptorRow> row_info;  ///< one per row
    std::vector<std::string> categories;  ///< categories with at least one complete model
    std::vector<ModelInfo> models;        ///< complete models, by (category, name)

    std::size_t rows() const { return row_info.size(); }
    std::span<const float> row(std::size_t i) const {
        const auto dim = static_cast<std::size_t>(kind.dimension);
        return {data.data() + i * dim, dim};
    }
};

/// An esf training database. Every SQLite problem (not a database, truncated, wrong schema,
/// locked, disk full) throws esf::IoError whose message starts with the file name.
class Database {
  public:
    /// Opens (kWrite: creates if needed) the database at `path`. Throws esf::IoError when the
    /// file is missing (kRead), is not an esf database, is truncated or has another schema, and
    /// for kWrite when the file is read-only or another writer (in any process) has it open:
    /// "database is in use by another training". A writer holds that lock until it is
    /// destroyed; readers take none.
    explicit Database(const std::string& path, OpenMode mode = OpenMode::kRead);
    ~Database();
    Database(Database&&) noexcept;
    Database& operator=(Database&&) noexcept;

    const std::string& path() const;
    bool writable() const;

    /// The stored settings (empty for a new database).
    Settings settings() const;
    /// Replaces all settings (one transaction).
    void set_settings(const Settings& settings);

    /// Registers a descriptor kind; a no-op when it is already stored with the same version and
    /// dimension. Throws std::invalid_argument when the name is stored with others.
    void add_descriptor_kind(const DescriptorKind& kind);
    std::vector<DescriptorKind> descriptor_kinds() const;

    /// Writes a model, its views and their descriptors of kind `descriptor` in one transaction,
    /// replacing a stored model of the same category and name. Throws std::invalid_argument for
    /// an unknown kind, empty names, duplicate view indices, non-finite values, descriptor
    /// lengths that are not a multiple of the kind's dimension, and a surface that
    /// check_model_surface() refuses, whose scale is not the model's or that a failed model has.
    void write_model(const ModelEntry& model, const std::string& descriptor);

    /// Status of a stored model, std::nullopt when absent.
    std::optional<ModelStatus> model_status(const std::string& category,
                                            const std::string& name) const;
    /// All stored models, by (category, name).
    std::vector<ModelInfo> models() const;
    /// The views of one model in index order, with their descriptors of kind `descriptor`
    /// (empty: the only kind stored). Throws std::invalid_argument when the model is absent.
    std::vector<ViewEntry> views(const std::string& category, const std::string& name,
                                 const std::string& descriptor = {}) const;

    /// The stored surface of a model; std::nullopt when the model is absent or none is stored
    /// (databases trained before surfaces were stored). Throws esf::IoError naming the file for
    /// a stored surface that is corrupt (check_model_surface()).
    std::optional<ModelSurface> model_surface(const std::string& category,
                                              const std::string& name) const;

    DatabaseSummary summary() const;

    /// Loads every descriptor of kind `descriptor` (empty: the only kind stored) of the complete
    /// models. Throws std::invalid_argument when the kind is absent or ambiguous.
    DescriptorMatrix load_descriptors(const std::string& descriptor = {}) const;

    /// A fingerprint (16 hex digits) of what weights of the kind are learned on: the complete
    /// models (category, name, scale) and their count of descriptors of the kind. Training,
    /// retraining or removing a model changes it.
    std::string content_fingerprint(const std::string& descriptor = {}) const;
    /// Learned weights of the descriptor's blocks (ESF: ten sub-histograms), replacing earlier
    /// ones, stored with the database's content_fingerprint(). Throws std::invalid_argument for
    /// an empty vector, a weight that is zero, negative or not finite, or an unknown kind; and
    /// esf::IoError when `learned_on` (the fingerprint read with the descriptors the weights were
    /// learned from; empty: not checked) is no longer the database's.
    void set_weights(std::span<const float> weights, const std::string& descriptor = {},
                     const std::string& learned_on = {});
    /// The stored weights when they were learned on the database as it is now; std::nullopt
    /// when none were set or when they are stale (weights_are_stale()).
    std::optional<std::vector<float>> weights(const std::string& descriptor = {}) const;
    /// The stored weights whatever they were learned on, std::nullopt when none were set.
    std::optional<std::vector<float>> stored_weights(const std::string& descriptor = {}) const;
    /// True when weights are stored but the database changed since they were learned (a model
    /// trained, replaced or removed), or they were stored by a version of esf that did not
    /// record what they were learned on. weights() ignores stale weights.
    bool weights_are_stale(const std::string& descriptor = {}) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace esf
