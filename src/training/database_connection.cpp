// The open database behind esf::Database (training/database_connection.hpp): connecting, the
// first read after an interrupted write, the writer's lock, the schema's checks and creation,
// and the queries the API shares.

#include "training/database_connection.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <set>
#include <stdexcept>

#include "esf/core/error.hpp"
#include "training/database_fingerprint.hpp"
#include "training/database_lock.hpp"
#include "training/database_schema.hpp"

namespace esf {

namespace {

/// "a, b, c": the names of `kinds`.
std::string join_names(const std::vector<DescriptorKind>& kinds) {
    std::string out;
    for (const auto& k : kinds) out += (out.empty() ? "" : ", ") + k.name;
    return out;
}

}  // namespace

Database::Impl::~Impl() {
    if (db && wal) sqlite3_exec(db, "PRAGMA journal_mode = DELETE", nullptr, nullptr, nullptr);
    sqlite3_close_v2(db);
    // Closed after SQLite: closing a descriptor of the file drops the process's fcntl locks.
    if (lock_fd >= 0) ::close(lock_fd);
}

void Database::Impl::fail(const std::string& reason) const {
    throw IoError(file_message(path, 0, reason));
}

void Database::Impl::exec(const char* sql) {
    char* message = nullptr;
    if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
        std::string reason = message ? message : sqlite3_errmsg(db);
        sqlite3_free(message);
        fail(reason);
    }
}

std::int64_t Database::Impl::pragma(const char* sql) const {
    SqliteStatement s = prepare(sql);
    return s.step() ? s.int64(0) : 0;
}

void Database::Impl::require_writable() const {
    if (mode != OpenMode::kWrite)
        throw std::invalid_argument(file_message(path, 0, "database is opened read-only"));
}

void Database::Impl::connect(int flags) {
    sqlite3_close_v2(db);
    db = nullptr;
    const int rc = sqlite3_open_v2(path.c_str(), &db, flags, nullptr);
    if (rc != SQLITE_OK) fail(db ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
    sqlite3_extended_result_codes(db, 1);
    sqlite3_busy_timeout(db, detail::kBusyTimeoutMs);
}

void Database::Impl::first_read() {
    const char* probe = "SELECT count(*) FROM sqlite_master";
    if (sqlite3_exec(db, probe, nullptr, nullptr, nullptr) == SQLITE_OK) return;
    if (mode == OpenMode::kRead && sqlite3_extended_errcode(db) == SQLITE_READONLY_ROLLBACK) {
        connect(SQLITE_OPEN_READWRITE);
        if (sqlite3_exec(db, probe, nullptr, nullptr, nullptr) != SQLITE_OK)
            fail(std::string("an interrupted write left a journal (") + path +
                 "-journal) that could not be rolled back: " + sqlite3_errmsg(db));
        connect(SQLITE_OPEN_READONLY);
        if (sqlite3_exec(db, probe, nullptr, nullptr, nullptr) == SQLITE_OK) return;
    }
    fail(sqlite3_errmsg(db));
}

void Database::Impl::lock_for_writing() {
    if (sqlite3_db_readonly(db, "main") == 1) fail("cannot write: the file is read-only");
    lock_fd = detail::lock_database_for_writing(path);
}

void Database::Impl::open() {
    connect(mode == OpenMode::kWrite ? SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE
                                     : SQLITE_OPEN_READONLY);
    if (mode == OpenMode::kWrite) lock_for_writing();
    first_read();
    check_schema();  // before any change: a file that is not ours is left untouched
    exec("PRAGMA foreign_keys = ON");
    if (mode == OpenMode::kWrite) {
        exec(detail::kWriterPragmas);
        wal = true;
        exec(detail::kWeightsBasis);
        exec(detail::kModelSurfaces);
    }
}

bool Database::Impl::has_table(const char* name) const {
    SqliteStatement s = prepare("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?");
    s.bind(1, std::string(name));
    return s.step();
}

std::string Database::Impl::fingerprint(std::int64_t kind_id) const {
    return detail::content_fingerprint(db, path, kind_id);
}

std::string Database::Impl::weights_basis(std::int64_t kind_id) const {
    if (!has_table("weights_basis")) return {};
    SqliteStatement s = prepare("SELECT fingerprint FROM weights_basis WHERE kind_id = ?");
    s.bind(1, kind_id);
    return s.step() ? s.text(0) : std::string();
}

void Database::Impl::check_schema() {
    // Reading sqlite_master makes SQLite parse the file: "file is not a database" and
    // hot-journal recovery surface here.
    std::set<std::string> tables;
    {
        SqliteStatement s = prepare("SELECT name FROM sqlite_master WHERE type = 'table'");
        while (s.step()) tables.insert(s.text(0));
    }
    const auto application_id = pragma("PRAGMA application_id");
    const auto version = pragma("PRAGMA user_version");
    if (tables.empty() && application_id == 0) {
        if (mode != OpenMode::kWrite) fail("empty SQLite database, not an esf database");
        create_schema();
        return;
    }
    if (application_id != detail::kApplicationId)
        fail("not an esf database (SQLite application id " + std::to_string(application_id) + ")");
    if (version != kDatabaseSchemaVersion)
        fail("esf database schema version " + std::to_string(version) +
             ", this version of esf reads version " + std::to_string(kDatabaseSchemaVersion));
    for (const char* table : detail::kTables)
        if (!tables.count(table))
            fail(std::string("corrupt esf database: table '") + table + "' is missing");
}

void Database::Impl::create_schema() {
    exec(detail::kPageSize);  // takes effect on a file without pages only
    exec("BEGIN IMMEDIATE");
    try {
        exec(detail::kSchema);
        exec(("PRAGMA application_id = " + std::to_string(detail::kApplicationId)).c_str());
        exec(("PRAGMA user_version = " + std::to_string(kDatabaseSchemaVersion)).c_str());
        exec("COMMIT");
    } catch (...) {
        sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
        throw;
    }
}

std::vector<DescriptorKind> Database::Impl::kinds() const {
    std::vector<DescriptorKind> out;
    SqliteStatement s =
        prepare("SELECT name, version, dimension FROM descriptor_kinds ORDER BY name");
    while (s.step()) out.push_back({s.text(0), s.integer(1), s.integer(2)});
    return out;
}

std::pair<std::int64_t, DescriptorKind> Database::Impl::kind(const std::string& name) const {
    if (name.empty()) {
        const auto all = kinds();
        if (all.empty())
            throw std::invalid_argument(file_message(path, 0, "no descriptors stored"));
        if (all.size() > 1)
            throw std::invalid_argument(file_message(
                path, 0,
                "several descriptor kinds stored (" + join_names(all) + "); name the one to use"));
        return kind(all.front().name);
    }
    SqliteStatement s =
        prepare("SELECT id, name, version, dimension FROM descriptor_kinds WHERE name = ?");
    s.bind(1, name);
    if (!s.step())
        throw std::invalid_argument(
            file_message(path, 0,
                         "no descriptors of kind '" + name + "' (stored: " +
                             (kinds().empty() ? std::string("none") : join_names(kinds())) + ")"));
    return {s.int64(0), {s.text(1), s.integer(2), s.integer(3)}};
}

std::vector<std::pair<std::int64_t, ModelInfo>> Database::Impl::models() const {
    std::vector<std::pair<std::int64_t, ModelInfo>> out;
    SqliteStatement s = prepare(
        "SELECT m.id, c.name, m.name, m.file, m.grp, m.scale, m.status, m.error,"
        " (SELECT count(*) FROM views v WHERE v.model_id = m.id AND v.skipped = 0),"
        " (SELECT count(*) FROM views v WHERE v.model_id = m.id AND v.skipped != 0)"
        " FROM models m JOIN categories c ON c.id = m.category_id"
        " ORDER BY c.name, m.name");
    while (s.step()) {
        ModelInfo m;
        m.category = s.text(1);
        m.name = s.text(2);
        m.file = s.text(3);
        m.group = s.text(4);
        m.scale = s.real(5);
        m.status = s.text(6) == "complete" ? ModelStatus::kComplete : ModelStatus::kFailed;
        m.error = s.text(7);
        m.views = s.size(8);
        m.skipped_views = s.size(9);
        out.emplace_back(s.int64(0), std::move(m));
    }
    return out;
}

std::optional<std::int64_t> Database::Impl::model_id(const std::string& category,
                                                     const std::string& name) const {
    SqliteStatement s = prepare(
        "SELECT m.id FROM models m JOIN categories c ON c.id = m.category_id"
        " WHERE c.name = ? AND m.name = ?");
    s.bind(1, category).bind(2, name);
    if (!s.step()) return std::nullopt;
    return s.int64(0);
}

}  // namespace esf
