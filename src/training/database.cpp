#include "esf/training/database.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "esf/core/error.hpp"

namespace esf {

static_assert(std::endian::native == std::endian::little,
              "descriptor blobs are stored as little-endian float32");

namespace {

constexpr std::int32_t kApplicationId = 0x45534631;  // "ESF1"
constexpr int kBusyTimeoutMs = 10000;
constexpr int kPoseFloats = 16;
// Writers use a write-ahead log: a commit appends to it and syncs it once (about 5 ms, where a
// rollback journal needs about 20 ms), and readers never block the writer. A writer that closes
// cleanly switches the file back to a rollback journal (checkpointing the log into it), so the
// database is one self-contained file that read-only opens never add files to. A writer that is
// killed leaves the log beside the file; the next open replays its committed transactions.
// 16 KiB pages hold six 2.5 KiB ESF rows (4 KiB pages hold one, wasting 40 % of the file).
constexpr const char* kWriterPragmas = "PRAGMA journal_mode = WAL; PRAGMA synchronous = FULL;";
constexpr const char* kPageSize = "PRAGMA page_size = 16384";

constexpr const char* kSchema = R"sql(
CREATE TABLE settings(
    key TEXT PRIMARY KEY NOT NULL,
    value NOT NULL);
CREATE TABLE categories(
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL UNIQUE);
CREATE TABLE models(
    id INTEGER PRIMARY KEY,
    category_id INTEGER NOT NULL REFERENCES categories(id),
    name TEXT NOT NULL,
    file TEXT NOT NULL,
    grp TEXT NOT NULL,
    scale REAL NOT NULL,
    status TEXT NOT NULL CHECK(status IN ('complete', 'failed')),
    error TEXT NOT NULL DEFAULT '',
    UNIQUE(category_id, name));
CREATE TABLE views(
    id INTEGER PRIMARY KEY,
    model_id INTEGER NOT NULL REFERENCES models(id) ON DELETE CASCADE,
    view_index INTEGER NOT NULL,
    points INTEGER NOT NULL,
    pose BLOB NOT NULL,
    skipped INTEGER NOT NULL,
    skip_reason TEXT NOT NULL DEFAULT '',
    UNIQUE(model_id, view_index));
CREATE TABLE descriptor_kinds(
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL UNIQUE,
    version INTEGER NOT NULL,
    dimension INTEGER NOT NULL CHECK(dimension > 0));
CREATE TABLE descriptors(
    id INTEGER PRIMARY KEY,
    view_id INTEGER NOT NULL REFERENCES views(id) ON DELETE CASCADE,
    kind_id INTEGER NOT NULL REFERENCES descriptor_kinds(id),
    signature INTEGER NOT NULL,
    data BLOB NOT NULL,
    UNIQUE(view_id, kind_id, signature));
CREATE TABLE weights(
    kind_id INTEGER PRIMARY KEY REFERENCES descriptor_kinds(id),
    data BLOB NOT NULL);
)sql";

// What stored weights were learned on (Database::content_fingerprint). Not in kTables: files
// written before it existed lack it, and a writer adds it.
constexpr const char* kWeightsBasis = R"sql(
CREATE TABLE IF NOT EXISTS weights_basis(
    kind_id INTEGER PRIMARY KEY REFERENCES descriptor_kinds(id),
    fingerprint TEXT NOT NULL);
)sql";

/// FNV-1a, 64 bits: a content fingerprint, not a security measure.
class Fnv1a {
  public:
    void add(const std::string& text) {
        for (const char c : text) byte(static_cast<unsigned char>(c));
        byte(0);  // a separator, so that ("ab", "c") and ("a", "bc") differ
    }
    std::string hex() const {
        static constexpr char kDigits[] = "0123456789abcdef";
        std::string out(16, '0');
        for (int i = 0; i < 16; ++i) out[15 - i] = kDigits[(hash_ >> (4 * i)) & 0xf];
        return out;
    }

  private:
    void byte(unsigned char b) {
        hash_ ^= b;
        hash_ *= 0x100000001b3ull;
    }
    std::uint64_t hash_ = 0xcbf29ce484222325ull;
};

constexpr std::array<const char*, 7> kTables = {
    "settings", "categories", "models", "views", "descriptor_kinds", "descriptors", "weights"};

/// Reads the 100-byte SQLite header to give precise messages for files that are not SQLite
/// databases or were cut short (SQLite itself only notices when it reads a missing page).
void check_file_header(const std::string& path, OpenMode mode) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const auto status = fs::status(path, ec);
    if (!fs::exists(status)) {
        if (mode == OpenMode::kRead) throw IoError(file_message(path, 0, "no such file"));
        return;
    }
    if (fs::is_directory(status)) throw IoError(file_message(path, 0, "is a directory"));
    const auto size = fs::file_size(path, ec);
    if (ec) throw IoError(file_message(path, 0, "cannot read: " + ec.message()));
    if (size == 0) {
        if (mode == OpenMode::kRead)
            throw IoError(file_message(path, 0, "empty file, not an esf database"));
        return;  // SQLite initialises an empty file as a new database
    }
    std::array<unsigned char, 100> header{};
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(file_message(path, 0, "cannot open for reading"));
    in.read(reinterpret_cast<char*>(header.data()), header.size());
    const auto got = static_cast<std::size_t>(in.gcount());
    static constexpr char kMagic[] = "SQLite format 3";  // 16 bytes with the terminating NUL
    if (got < 16 || std::memcmp(header.data(), kMagic, 16) != 0)
        throw IoError(file_message(path, 0, "not an SQLite database (esf databases are SQLite)"));
    if (got < header.size())
        throw IoError(file_message(path, 0,
                                   "truncated SQLite database (" + std::to_string(size) +
                                       " bytes, shorter than its header)"));
    auto be32 = [&](std::size_t at) {
        return std::uint32_t{header[at]} << 24 | std::uint32_t{header[at + 1]} << 16 |
               std::uint32_t{header[at + 2]} << 8 | std::uint32_t{header[at + 3]};
    };
    std::uint64_t page_size = std::uint32_t{header[16]} << 8 | header[17];
    if (page_size == 1) page_size = 65536;
    const std::uint64_t pages = be32(28);
    // The page count in the header is valid when the change counter matches version-valid-for.
    // With a write-ahead log beside the file the log may hold the newer pages, so skip then.
    const bool count_valid = pages != 0 && be32(24) == be32(92);
    if (count_valid && !fs::exists(path + "-wal") && size < pages * page_size)
        throw IoError(file_message(path, 0,
                                   "truncated SQLite database (" + std::to_string(size) +
                                       " bytes, its header says " +
                                       std::to_string(pages * page_size) + ")"));
}

std::vector<unsigned char> float_blob(std::span<const float> values) {
    std::vector<unsigned char> blob(values.size_bytes());
    if (!values.empty()) std::memcpy(blob.data(), values.data(), values.size_bytes());
    return blob;
}

bool all_finite(std::span<const float> values) {
    return std::all_of(values.begin(), values.end(), [](float v) { return std::isfinite(v); });
}

std::string join_names(const std::vector<DescriptorKind>& kinds) {
    std::string out;
    for (const auto& k : kinds) out += (out.empty() ? "" : ", ") + k.name;
    return out;
}

}  // namespace

std::string to_string(const SettingValue& value) {
    if (const auto* i = std::get_if<std::int64_t>(&value)) return std::to_string(*i);
    if (const auto* d = std::get_if<double>(&value)) {
        // Shortest form that reads back to the same double.
        std::string text;
        for (int precision = 1; precision <= 17; ++precision) {
            std::ostringstream out;
            out.precision(precision);
            out << *d;
            text = out.str();
            if (std::strtod(text.c_str(), nullptr) == *d) break;
        }
        return text;
    }
    return std::get<std::string>(value);
}

// ---------------------------------------------------------------------------------------------
// A thin RAII layer over sqlite3: every failure becomes an IoError naming the file.

namespace {

class Statement {
  public:
    Statement(sqlite3* db, const std::string& path, const char* sql) : db_(db), path_(&path) {
        if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) fail();
    }
    ~Statement() { sqlite3_finalize(stmt_); }
    Statement(const Statement&) = delete;
    Statement& operator=(const Statement&) = delete;

    Statement& bind(int i, std::int64_t v) { return check(sqlite3_bind_int64(stmt_, i, v)); }
    Statement& bind(int i, int v) { return bind(i, std::int64_t{v}); }
    Statement& bind(int i, std::size_t v) { return bind(i, static_cast<std::int64_t>(v)); }
    Statement& bind(int i, double v) { return check(sqlite3_bind_double(stmt_, i, v)); }
    Statement& bind(int i, const std::string& v) {
        return check(
            sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
    }
    Statement& bind(int i, const char* v) { return bind(i, std::string(v)); }
    Statement& bind_blob(int i, std::span<const float> v) {
        const auto blob = float_blob(v);
        return check(sqlite3_bind_blob(stmt_, i, blob.data(), static_cast<int>(blob.size()),
                                       SQLITE_TRANSIENT));
    }

    /// Steps once; true while a row is available.
    bool step() {
        const int rc = sqlite3_step(stmt_);
        if (rc == SQLITE_ROW) return true;
        if (rc == SQLITE_DONE) return false;
        fail();
    }
    void run() {
        while (step()) {
        }
        reset();
    }
    void reset() {
        sqlite3_reset(stmt_);
        sqlite3_clear_bindings(stmt_);
    }

    std::int64_t int64(int col) const { return sqlite3_column_int64(stmt_, col); }
    int integer(int col) const { return sqlite3_column_int(stmt_, col); }
    std::size_t size(int col) const { return static_cast<std::size_t>(int64(col)); }
    double real(int col) const { return sqlite3_column_double(stmt_, col); }
    std::string text(int col) const {
        const auto* p = sqlite3_column_text(stmt_, col);
        return p ? std::string(reinterpret_cast<const char*>(p),
                               static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col)))
                 : std::string();
    }
    int type(int col) const { return sqlite3_column_type(stmt_, col); }
    /// Copies a float32 blob of exactly `count` values into `out`.
    void floats(int col, float* out, std::size_t count, const char* what) const {
        const void* p = sqlite3_column_blob(stmt_, col);
        const auto bytes = static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col));
        if (bytes != count * sizeof(float))
            throw IoError(file_message(*path_, 0,
                                       std::string("corrupt database: ") + what + " holds " +
                                           std::to_string(bytes) + " bytes, expected " +
                                           std::to_string(count * sizeof(float))));
        if (count) std::memcpy(out, p, bytes);
    }
    std::vector<float> floats(int col) const {
        const auto bytes = static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col));
        std::vector<float> out(bytes / sizeof(float));
        floats(col, out.data(), out.size(), "a float array");
        return out;
    }

  private:
    Statement& check(int rc) {
        if (rc != SQLITE_OK) fail();
        return *this;
    }
    [[noreturn]] void fail() const { throw IoError(file_message(*path_, 0, sqlite3_errmsg(db_))); }

    sqlite3* db_;
    const std::string* path_;
    sqlite3_stmt* stmt_ = nullptr;
};

}  // namespace

struct Database::Impl {
    std::string path;
    OpenMode mode;
    sqlite3* db = nullptr;
    bool wal = false;  ///< this writer switched the file to write-ahead logging
    int lock_fd = -1;  ///< a writer's flock() on the file: one writer at a time

    Impl(std::string p, OpenMode m) : path(std::move(p)), mode(m) {}
    ~Impl() {
        if (db && wal) sqlite3_exec(db, "PRAGMA journal_mode = DELETE", nullptr, nullptr, nullptr);
        sqlite3_close_v2(db);
        // Closed after SQLite: closing a descriptor of the file drops the process's fcntl locks.
        if (lock_fd >= 0) ::close(lock_fd);
    }

    [[noreturn]] void fail(const std::string& reason) const {
        throw IoError(file_message(path, 0, reason));
    }
    void exec(const char* sql) {
        char* message = nullptr;
        if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
            std::string reason = message ? message : sqlite3_errmsg(db);
            sqlite3_free(message);
            fail(reason);
        }
    }
    Statement prepare(const char* sql) const { return Statement(db, path, sql); }
    std::int64_t pragma(const char* sql) const {
        Statement s = prepare(sql);
        return s.step() ? s.int64(0) : 0;
    }
    void require_writable() const {
        if (mode != OpenMode::kWrite)
            throw std::invalid_argument(file_message(path, 0, "database is opened read-only"));
    }

    void connect(int flags) {
        sqlite3_close_v2(db);
        db = nullptr;
        const int rc = sqlite3_open_v2(path.c_str(), &db, flags, nullptr);
        if (rc != SQLITE_OK) fail(db ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
        sqlite3_extended_result_codes(db, 1);
        sqlite3_busy_timeout(db, kBusyTimeoutMs);
    }

    /// First read of the file. A writer killed inside a transaction leaves a hot journal that
    /// SQLite must roll back before anyone reads; a read-only connection cannot, so a short
    /// read-write connection (which never creates the file) restores the last committed state.
    void first_read() {
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

    /// One writer at a time: an exclusive flock() on the file, held until the writer closes.
    /// (SQLite's own locks last one transaction, so two trainings would interleave models and
    /// race to create the schema.) Readers take no lock and are never refused.
    void lock_for_writing() {
        if (sqlite3_db_readonly(db, "main") == 1) fail("cannot write: the file is read-only");
        lock_fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (lock_fd < 0) fail(std::string("cannot open for locking: ") + std::strerror(errno));
        if (::flock(lock_fd, LOCK_EX | LOCK_NB) != 0) {
            const int error = errno;
            ::close(lock_fd);
            lock_fd = -1;
            if (error == EWOULDBLOCK) fail("database is in use by another training");
            fail(std::string("cannot lock: ") + std::strerror(error));
        }
    }

    void open() {
        connect(mode == OpenMode::kWrite ? SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE
                                         : SQLITE_OPEN_READONLY);
        if (mode == OpenMode::kWrite) lock_for_writing();
        first_read();
        check_schema();  // before any change: a file that is not ours is left untouched
        exec("PRAGMA foreign_keys = ON");
        if (mode == OpenMode::kWrite) {
            exec(kWriterPragmas);
            wal = true;
            exec(kWeightsBasis);
        }
    }

    bool has_table(const char* name) const {
        Statement s = prepare("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?");
        s.bind(1, std::string(name));
        return s.step();
    }

    /// See Database::content_fingerprint().
    std::string fingerprint(std::int64_t kind_id) const {
        Statement s = prepare(
            "SELECT c.name, m.name, m.scale,"
            " (SELECT count(*) FROM descriptors d JOIN views v ON v.id = d.view_id"
            "  WHERE v.model_id = m.id AND d.kind_id = ?)"
            " FROM models m JOIN categories c ON c.id = m.category_id"
            " WHERE m.status = 'complete' ORDER BY c.name, m.name");
        s.bind(1, kind_id);
        Fnv1a hash;
        while (s.step()) {
            hash.add(s.text(0));
            hash.add(s.text(1));
            std::ostringstream scale;
            scale.precision(17);
            scale << s.real(2);
            hash.add(scale.str());
            hash.add(std::to_string(s.int64(3)));
        }
        return hash.hex();
    }

    /// The fingerprint stored with the weights of `kind_id`; empty when there is none.
    std::string weights_basis(std::int64_t kind_id) const {
        if (!has_table("weights_basis")) return {};
        Statement s = prepare("SELECT fingerprint FROM weights_basis WHERE kind_id = ?");
        s.bind(1, kind_id);
        return s.step() ? s.text(0) : std::string();
    }

    void check_schema() {
        // Reading sqlite_master makes SQLite parse the file: "file is not a database" and
        // hot-journal recovery surface here.
        std::set<std::string> tables;
        {
            Statement s = prepare("SELECT name FROM sqlite_master WHERE type = 'table'");
            while (s.step()) tables.insert(s.text(0));
        }
        const auto application_id = pragma("PRAGMA application_id");
        const auto version = pragma("PRAGMA user_version");
        if (tables.empty() && application_id == 0) {
            if (mode != OpenMode::kWrite) fail("empty SQLite database, not an esf database");
            create_schema();
            return;
        }
        if (application_id != kApplicationId)
            fail("not an esf database (SQLite application id " + std::to_string(application_id) +
                 ")");
        if (version != kDatabaseSchemaVersion)
            fail("esf database schema version " + std::to_string(version) +
                 ", this version of esf reads version " + std::to_string(kDatabaseSchemaVersion));
        for (const char* table : kTables)
            if (!tables.count(table))
                fail(std::string("corrupt esf database: table '") + table + "' is missing");
    }

    void create_schema() {
        exec(kPageSize);  // takes effect on a file without pages only
        exec("BEGIN IMMEDIATE");
        try {
            exec(kSchema);
            exec(("PRAGMA application_id = " + std::to_string(kApplicationId)).c_str());
            exec(("PRAGMA user_version = " + std::to_string(kDatabaseSchemaVersion)).c_str());
            exec("COMMIT");
        } catch (...) {
            sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
            throw;
        }
    }

    /// Runs `body` in one write transaction; rolls back when it throws.
    template <class Body>
    void transaction(Body&& body) {
        require_writable();
        exec("BEGIN IMMEDIATE");
        try {
            body();
            exec("COMMIT");
        } catch (...) {
            sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
            throw;
        }
    }

    std::vector<DescriptorKind> kinds() const {
        std::vector<DescriptorKind> out;
        Statement s =
            prepare("SELECT name, version, dimension FROM descriptor_kinds ORDER BY name");
        while (s.step()) out.push_back({s.text(0), s.integer(1), s.integer(2)});
        return out;
    }

    /// The kind named `name`, or the only stored kind when `name` is empty, with its row id.
    std::pair<std::int64_t, DescriptorKind> kind(const std::string& name) const {
        if (name.empty()) {
            const auto all = kinds();
            if (all.empty())
                throw std::invalid_argument(file_message(path, 0, "no descriptors stored"));
            if (all.size() > 1)
                throw std::invalid_argument(file_message(path, 0,
                                                         "several descriptor kinds stored (" +
                                                             join_names(all) +
                                                             "); name the one to use"));
            return kind(all.front().name);
        }
        Statement s =
            prepare("SELECT id, name, version, dimension FROM descriptor_kinds WHERE name = ?");
        s.bind(1, name);
        if (!s.step())
            throw std::invalid_argument(file_message(
                path, 0,
                "no descriptors of kind '" + name + "' (stored: " +
                    (kinds().empty() ? std::string("none") : join_names(kinds())) + ")"));
        return {s.int64(0), {s.text(1), s.integer(2), s.integer(3)}};
    }

    /// Stored models with their row ids, by (category, name).
    std::vector<std::pair<std::int64_t, ModelInfo>> models() const {
        std::vector<std::pair<std::int64_t, ModelInfo>> out;
        Statement s = prepare(
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

    std::optional<std::int64_t> model_id(const std::string& category,
                                         const std::string& name) const {
        Statement s = prepare(
            "SELECT m.id FROM models m JOIN categories c ON c.id = m.category_id"
            " WHERE c.name = ? AND m.name = ?");
        s.bind(1, category).bind(2, name);
        if (!s.step()) return std::nullopt;
        return s.int64(0);
    }
};

// ---------------------------------------------------------------------------------------------

Database::Database(const std::string& path, OpenMode mode)
    : impl_(std::make_unique<Impl>(path, mode)) {
    if (path.empty()) throw std::invalid_argument("database path is empty");
    check_file_header(path, mode);
    impl_->open();
}

Database::~Database() = default;
Database::Database(Database&&) noexcept = default;
Database& Database::operator=(Database&&) noexcept = default;

const std::string& Database::path() const { return impl_->path; }
bool Database::writable() const { return impl_->mode == OpenMode::kWrite; }

Settings Database::settings() const {
    Settings out;
    Statement s = impl_->prepare("SELECT key, value FROM settings ORDER BY key");
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
        Statement s = impl_->prepare("INSERT INTO settings(key, value) VALUES (?, ?)");
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
        Statement s = impl_->prepare(
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

    impl_->transaction([&] {
        if (const auto old = impl_->model_id(model.category, model.name)) {
            Statement del = impl_->prepare("DELETE FROM models WHERE id = ?");
            del.bind(1, *old).run();
        }
        Statement cat = impl_->prepare("INSERT OR IGNORE INTO categories(name) VALUES (?)");
        cat.bind(1, model.category).run();
        Statement cat_id = impl_->prepare("SELECT id FROM categories WHERE name = ?");
        cat_id.bind(1, model.category);
        cat_id.step();
        const std::int64_t category_id = cat_id.int64(0);

        Statement ins = impl_->prepare(
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

        Statement view_ins = impl_->prepare(
            "INSERT INTO views(model_id, view_index, points, pose, skipped, skip_reason)"
            " VALUES (?, ?, ?, ?, ?, ?)");
        Statement desc_ins = impl_->prepare(
            "INSERT INTO descriptors(view_id, kind_id, signature, data) VALUES (?, ?, ?, ?)");
        for (const auto& view : model.views) {
            view_ins.bind(1, model_id)
                .bind(2, view.index)
                .bind(3, view.points)
                .bind_blob(4, std::span<const float>(view.pose.data(), kPoseFloats))
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
    });
}

std::optional<ModelStatus> Database::model_status(const std::string& category,
                                                  const std::string& name) const {
    Statement s = impl_->prepare(
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
    Statement s = impl_->prepare(
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
            s.floats(2, view.pose.data(), kPoseFloats, "a view pose");
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
    return out;
}

DescriptorMatrix Database::load_descriptors(const std::string& descriptor) const {
    const auto [kind_id, kind] = impl_->kind(descriptor);
    DescriptorMatrix out;
    out.kind = kind;
    const auto dim = static_cast<std::size_t>(kind.dimension);
    {
        Statement count = impl_->prepare("SELECT count(*) FROM descriptors WHERE kind_id = ?");
        count.bind(1, kind_id);
        count.step();
        out.data.reserve(count.size(0) * dim);
        out.row_info.reserve(count.size(0));
    }
    Statement s = impl_->prepare(
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
            s.floats(1, row.pose.data(), kPoseFloats, "a view pose");
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
        Statement s = impl_->prepare("INSERT OR REPLACE INTO weights(kind_id, data) VALUES (?, ?)");
        s.bind(1, kind_id).bind_blob(2, weights).run();
        Statement b = impl_->prepare(
            "INSERT OR REPLACE INTO weights_basis(kind_id, fingerprint) VALUES (?, ?)");
        b.bind(1, kind_id).bind(2, fingerprint).run();
    });
}

std::optional<std::vector<float>> Database::stored_weights(const std::string& descriptor) const {
    const auto kind_id = impl_->kind(descriptor).first;
    Statement s = impl_->prepare("SELECT data FROM weights WHERE kind_id = ?");
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
