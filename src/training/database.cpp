// esf::Database: its API over the open connection (database_connection.hpp). The file's format
// is database_schema.hpp, the writer's lock database_lock.hpp, the fingerprint of what the
// descriptors were computed from database_fingerprint.hpp.

#include "esf/training/database.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/number_text.hpp"
#include "esf/core/error.hpp"
#include "training/database_connection.hpp"
#include "training/database_schema.hpp"

namespace esf {

static_assert(std::endian::native == std::endian::little,
              "descriptor blobs are stored as little-endian float32");

namespace {

bool all_finite(std::span<const float> values) {
    return std::all_of(values.begin(), values.end(), [](float v) { return std::isfinite(v); });
}

}  // namespace

std::string to_string(const SettingValue& value) {
    if (const auto* i = std::get_if<std::int64_t>(&value)) return std::to_string(*i);
    if (const auto* d = std::get_if<double>(&value)) {
        // Shortest form that reads back to the same double.
        std::string text;
        for (int precision = 1; precision <= 17; ++precision) {
            text = detail::significant_text(*d, precision);
            if (std::strtod(text.c_str(), nullptr) == *d) break;
        }
        return text;
    }
    return std::get<std::string>(value);
}

Database::Database(const std::string& path, OpenMode mode)
    : impl_(std::make_unique<Impl>(path, mode)) {
    if (path.empty()) throw std::invalid_argument("database path is empty");
    detail::check_database_file_header(path, mode);
    impl_->open();
}

Database::~Database() = default;
Database::Database(Database&&) noexcept = default;
Database& Database::operator=(Database&&) noexcept = default;

const std::string& Database::path() const { return impl_->path; }
bool Database::writable() const { return impl_->mode == OpenMode::kWrite; }

Settings Database::settings() const {
    Settings out;
    SqliteStatement s = impl_->prepare("SELECT key, value FROM settings ORDER BY key");
    while (s.step()) {
        switch (s.type(1)) {
            case SQLITE_INTEGER:
                out[s.text(0)] = s.int64(1);
                break;
            case SQLITE_FLOAT:
                out[s.text(0)] = s.real(1);
                break;
            default:
                out[s.text(0)] = s.text(1);
        }
    }
    return out;
}

void Database::set_settings(const Settings& settings) {
    impl_->transaction([&] {
        impl_->exec("DELETE FROM settings");
        SqliteStatement s = impl_->prepare("INSERT INTO settings(key, value) VALUES (?, ?)");
        for (const auto& [key, value] : settings) {
            if (key.empty()) throw std::invalid_argument("setting with an empty name");
            s.bind(1, key);
            std::visit([&](const auto& v) { s.bind(2, v); }, value);
            s.run();
        }
    });
}

void Database::add_descriptor_kind(const DescriptorKind& kind) {
    if (kind.name.empty()) throw std::invalid_argument("descriptor kind with an empty name");
    if (kind.dimension <= 0)
        throw std::invalid_argument("descriptor kind '" + kind.name +
                                    "': dimension must be > 0, got " +
                                    std::to_string(kind.dimension));
    impl_->require_writable();
    for (const auto& stored : impl_->kinds()) {
        if (stored.name != kind.name) continue;
        if (stored == kind) return;
        throw std::invalid_argument(file_message(
            impl_->path, 0,
            "descriptor '" + kind.name + "' is stored with version " +
                std::to_string(stored.version) + " and dimension " +
                std::to_string(stored.dimension) + ", not version " + std::to_string(kind.version) +
                " and dimension " + std::to_string(kind.dimension)));
    }
    impl_->transaction([&] {
        SqliteStatement s = impl_->prepare(
            "INSERT INTO descriptor_kinds(name, version, dimension) VALUES (?, ?, ?)");
        s.bind(1, kind.name).bind(2, kind.version).bind(3, kind.dimension).run();
    });
}

std::vector<DescriptorKind> Database::descriptor_kinds() const { return impl_->kinds(); }

void Database::write_model(const ModelEntry& model, const std::string& descriptor) {
    impl_->require_writable();
    const std::string what = "model '" + model.category + "/" + model.name + "'";
    if (model.category.empty() || model.name.empty())
        throw std::invalid_argument("model with an empty category or name ('" + model.category +
                                    "/" + model.name + "')");
    if (!std::isfinite(model.scale) || model.scale <= 0.0)
        throw std::invalid_argument(what + ": scale must be finite and > 0");
    if (!model.error.empty() && !model.views.empty())
        throw std::invalid_argument(what + ": a failed model has no views");
    const auto [kind_id, kind] = impl_->kind(descriptor);
    const auto dim = static_cast<std::size_t>(kind.dimension);
    std::set<int> indices;
    for (const auto& view : model.views) {
        const std::string vwhat = what + " view " + std::to_string(view.index);
        if (!indices.insert(view.index).second)
            throw std::invalid_argument(vwhat + ": duplicate view index");
        if (view.descriptors.size() % dim != 0)
            throw std::invalid_argument(vwhat + ": " + std::to_string(view.descriptors.size()) +
                                        " descriptor values, not a multiple of " +
                                        std::to_string(dim) + " (" + kind.name + ")");
        if (!all_finite(view.descriptors))
            throw std::invalid_argument(vwhat + ": non-finite descriptor value");
        if (!view.pose.allFinite()) throw std::invalid_argument(vwhat + ": non-finite pose");
        if (!view.descriptors.empty() && !view.skip_reason.empty())
            throw std::invalid_argument(vwhat + ": has descriptors and a skip reason");
    }
    if (model.surface) {
        if (!model.error.empty())
            throw std::invalid_argument(what + ": a failed model has no surface");
        check_model_surface(*model.surface, what);
        if (model.surface->points.size() > kMaxModelSurfacePoints)
            throw std::invalid_argument(what + ": more than " +
                                        std::to_string(kMaxModelSurfacePoints) + " surface points");
        if (model.surface->scale != model.scale)
            throw std::invalid_argument(what + ": the surface's scale is not the model's");
    }

    impl_->transaction([&] {
        if (const auto old = impl_->model_id(model.category, model.name)) {
            SqliteStatement del = impl_->prepare("DELETE FROM models WHERE id = ?");
            del.bind(1, *old).run();
        }
        SqliteStatement cat = impl_->prepare("INSERT OR IGNORE INTO categories(name) VALUES (?)");
        cat.bind(1, model.category).run();
        SqliteStatement cat_id = impl_->prepare("SELECT id FROM categories WHERE name = ?");
        cat_id.bind(1, model.category);
        cat_id.step();
        const std::int64_t category_id = cat_id.int64(0);

        SqliteStatement ins = impl_->prepare(
            "INSERT INTO models(category_id, name, file, grp, scale, status, error)"
            " VALUES (?, ?, ?, ?, ?, ?, ?)");
        ins.bind(1, category_id)
            .bind(2, model.name)
            .bind(3, model.file)
            .bind(4, model.group.empty() ? model.name : model.group)
            .bind(5, model.scale)
            .bind(6, model.error.empty() ? "complete" : "failed")
            .bind(7, model.error)
            .run();
        const std::int64_t model_id = sqlite3_last_insert_rowid(impl_->db);

        SqliteStatement view_ins = impl_->prepare(
            "INSERT INTO views(model_id, view_index, points, pose, skipped, skip_reason)"
            " VALUES (?, ?, ?, ?, ?, ?)");
        SqliteStatement desc_ins = impl_->prepare(
            "INSERT INTO descriptors(view_id, kind_id, signature, data) VALUES (?, ?, ?, ?)");
        for (const auto& view : model.views) {
            view_ins.bind(1, model_id)
                .bind(2, view.index)
                .bind(3, view.points)
                .bind_blob(4, std::span<const float>(view.pose.data(), detail::kPoseFloats))
                .bind(5, view.skipped() ? 1 : 0)
                .bind(6, view.skip_reason)
                .run();
            const std::int64_t view_id = sqlite3_last_insert_rowid(impl_->db);
            const std::size_t signatures = view.descriptors.size() / dim;
            for (std::size_t sig = 0; sig < signatures; ++sig) {
                desc_ins.bind(1, view_id)
                    .bind(2, kind_id)
                    .bind(3, sig)
                    .bind_blob(4, std::span<const float>(view.descriptors).subspan(sig * dim, dim))
                    .run();
            }
        }
        if (model.surface) {
            const ModelSurface& surface = *model.surface;
            const std::size_t floats = 3 * surface.points.size();
            SqliteStatement surface_ins = impl_->prepare(
                "INSERT INTO model_surfaces(model_id, scale, diameter, points, normals)"
                " VALUES (?, ?, ?, ?, ?)");
            surface_ins.bind(1, model_id)
                .bind(2, surface.scale)
                .bind(3, surface.diameter)
                .bind_blob(4, std::span<const float>(surface.points.front().data(), floats))
                .bind_blob(5, std::span<const float>(surface.normals.front().data(), floats))
                .run();
        }
    });
}

std::optional<ModelStatus> Database::model_status(const std::string& category,
                                                  const std::string& name) const {
    SqliteStatement s = impl_->prepare(
        "SELECT m.status FROM models m JOIN categories c ON c.id = m.category_id"
        " WHERE c.name = ? AND m.name = ?");
    s.bind(1, category).bind(2, name);
    if (!s.step()) return std::nullopt;
    return s.text(0) == "complete" ? ModelStatus::kComplete : ModelStatus::kFailed;
}

std::vector<ModelInfo> Database::models() const {
    std::vector<ModelInfo> out;
    for (auto& [id, info] : impl_->models()) out.push_back(std::move(info));
    return out;
}

std::vector<ViewEntry> Database::views(const std::string& category, const std::string& name,
                                       const std::string& descriptor) const {
    const auto id = impl_->model_id(category, name);
    if (!id)
        throw std::invalid_argument(
            file_message(impl_->path, 0, "no model '" + category + "/" + name + "'"));
    const auto kinds = impl_->kinds();
    const bool with_descriptors = !descriptor.empty() || !kinds.empty();
    std::int64_t kind_id = -1;
    std::size_t dim = 0;
    if (with_descriptors) {
        const auto [kid, kind] = impl_->kind(descriptor);
        kind_id = kid;
        dim = static_cast<std::size_t>(kind.dimension);
    }
    std::vector<ViewEntry> out;
    SqliteStatement s = impl_->prepare(
        "SELECT v.view_index, v.points, v.pose, v.skip_reason, d.data"
        " FROM views v LEFT JOIN descriptors d ON d.view_id = v.id AND d.kind_id = ?"
        " WHERE v.model_id = ? ORDER BY v.view_index, d.signature");
    s.bind(1, kind_id).bind(2, *id);
    while (s.step()) {
        const int index = s.integer(0);
        if (out.empty() || out.back().index != index) {
            ViewEntry view;
            view.index = index;
            view.points = s.size(1);
            s.floats(2, view.pose.data(), detail::kPoseFloats, "a view pose");
            view.skip_reason = s.text(3);
            out.push_back(std::move(view));
        }
        if (s.type(4) != SQLITE_NULL) {
            auto& d = out.back().descriptors;
            d.resize(d.size() + dim);
            s.floats(4, d.data() + d.size() - dim, dim, "a descriptor");
        }
    }
    return out;
}

std::optional<ModelSurface> Database::model_surface(const std::string& category,
                                                    const std::string& name) const {
    if (!impl_->has_table("model_surfaces")) return std::nullopt;
    const auto id = impl_->model_id(category, name);
    if (!id) return std::nullopt;
    SqliteStatement s = impl_->prepare(
        "SELECT scale, diameter, points, normals FROM model_surfaces WHERE model_id = ?");
    s.bind(1, *id);
    if (!s.step()) return std::nullopt;
    const std::string what = file_message(impl_->path, 0, "model '" + category + "/" + name + "'");
    auto read = [&](int col, const char* part) {
        const std::vector<float> values = s.floats(col);
        if (values.size() % 3 != 0 || values.size() / 3 > kMaxModelSurfacePoints)
            throw IoError(what + ": corrupt surface " + part + " (" +
                          std::to_string(values.size()) + " floats)");
        Points out(values.size() / 3);
        std::copy(values.begin(), values.end(), out.empty() ? nullptr : out.front().data());
        return out;
    };
    ModelSurface surface;
    surface.scale = s.real(0);
    surface.diameter = s.real(1);
    surface.points = read(2, "points");
    surface.normals = read(3, "normals");
    try {
        check_model_surface(surface, what);
    } catch (const std::invalid_argument& e) {
        throw IoError(std::string(e.what()) + " (a corrupt stored surface)");
    }
    return surface;
}

DatabaseSummary Database::summary() const {
    DatabaseSummary out;
    std::map<std::string, CategoryInfo> categories;
    for (const auto& [id, m] : impl_->models()) {
        auto& c = categories[m.category];
        c.name = m.category;
        if (m.status == ModelStatus::kComplete) {
            ++c.models;
            ++out.models;
        } else {
            ++c.failed_models;
            ++out.failed_models;
        }
        c.views += m.views;
        c.skipped_views += m.skipped_views;
        out.views += m.views;
        out.skipped_views += m.skipped_views;
    }
    for (auto& [name, c] : categories) out.categories.push_back(std::move(c));
    out.descriptor_kinds = impl_->kinds();
    if (impl_->has_table("model_surfaces")) {
        SqliteStatement s = impl_->prepare(
            "SELECT count(*) FROM model_surfaces s JOIN models m ON m.id = s.model_id"
            " WHERE m.status = 'complete'");
        s.step();
        out.surfaces = s.size(0);
    }
    return out;
}

DescriptorMatrix Database::load_descriptors(const std::string& descriptor) const {
    const auto [kind_id, kind] = impl_->kind(descriptor);
    DescriptorMatrix out;
    out.kind = kind;
    const auto dim = static_cast<std::size_t>(kind.dimension);
    {
        SqliteStatement count =
            impl_->prepare("SELECT count(*) FROM descriptors WHERE kind_id = ?");
        count.bind(1, kind_id);
        count.step();
        out.data.reserve(count.size(0) * dim);
        out.row_info.reserve(count.size(0));
    }
    SqliteStatement s = impl_->prepare(
        "SELECT v.view_index, v.pose, d.signature, d.data"
        " FROM views v JOIN descriptors d ON d.view_id = v.id"
        " WHERE v.model_id = ? AND d.kind_id = ? ORDER BY v.view_index, d.signature");
    for (auto& [model_id, info] : impl_->models()) {
        if (info.status != ModelStatus::kComplete) continue;
        if (out.categories.empty() || out.categories.back() != info.category)
            out.categories.push_back(info.category);
        const auto category = static_cast<std::uint32_t>(out.categories.size() - 1);
        const auto model = static_cast<std::uint32_t>(out.models.size());
        out.models.push_back(std::move(info));
        s.bind(1, model_id).bind(2, kind_id);
        while (s.step()) {
            DescriptorRow row;
            row.category = category;
            row.model = model;
            row.view_index = s.integer(0);
            s.floats(1, row.pose.data(), detail::kPoseFloats, "a view pose");
            row.signature = s.integer(2);
            out.data.resize(out.data.size() + dim);
            s.floats(3, out.data.data() + out.data.size() - dim, dim, "a descriptor");
            out.row_info.push_back(row);
        }
        s.reset();
    }
    return out;
}

std::string Database::content_fingerprint(const std::string& descriptor) const {
    return impl_->fingerprint(impl_->kind(descriptor).first);
}

void Database::set_weights(std::span<const float> weights, const std::string& descriptor,
                           const std::string& learned_on) {
    impl_->require_writable();
    if (weights.empty()) throw std::invalid_argument("weights are empty");
    for (std::size_t i = 0; i < weights.size(); ++i)
        if (!(std::isfinite(weights[i]) && weights[i] > 0.0f))
            throw std::invalid_argument("weight " + std::to_string(i) + " is " +
                                        std::to_string(weights[i]) +
                                        ": weights must be positive and finite");
    const auto kind_id = impl_->kind(descriptor).first;
    impl_->transaction([&] {
        const std::string fingerprint = impl_->fingerprint(kind_id);
        if (!learned_on.empty() && learned_on != fingerprint)
            impl_->fail("the database changed while its weights were learned; learn them again");
        SqliteStatement s =
            impl_->prepare("INSERT OR REPLACE INTO weights(kind_id, data) VALUES (?, ?)");
        s.bind(1, kind_id).bind_blob(2, weights).run();
        SqliteStatement b = impl_->prepare(
            "INSERT OR REPLACE INTO weights_basis(kind_id, fingerprint) VALUES (?, ?)");
        b.bind(1, kind_id).bind(2, fingerprint).run();
    });
}

std::optional<std::vector<float>> Database::stored_weights(const std::string& descriptor) const {
    const auto kind_id = impl_->kind(descriptor).first;
    SqliteStatement s = impl_->prepare("SELECT data FROM weights WHERE kind_id = ?");
    s.bind(1, kind_id);
    if (!s.step()) return std::nullopt;
    return s.floats(0);
}

bool Database::weights_are_stale(const std::string& descriptor) const {
    const auto kind_id = impl_->kind(descriptor).first;
    if (!stored_weights(descriptor)) return false;
    return impl_->weights_basis(kind_id) != impl_->fingerprint(kind_id);
}

std::optional<std::vector<float>> Database::weights(const std::string& descriptor) const {
    if (weights_are_stale(descriptor)) return std::nullopt;
    return stored_weights(descriptor);
}

}  // namespace esf
