#pragma once
// The open database behind esf::Database (database.cpp): the SQLite connection, its writer's
// lock and the statements the API shares (database_connection.cpp). Internal to the training
// layer.

#include <sqlite3.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "esf/training/database.hpp"
#include "training/sqlite_statement.hpp"

namespace esf {

using detail::SqliteStatement;

struct Database::Impl {
    std::string path;
    OpenMode mode;
    sqlite3* db = nullptr;
    bool wal = false;  ///< this writer switched the file to write-ahead logging
    int lock_fd = -1;  ///< a writer's flock() on the file: one writer at a time

    Impl(std::string p, OpenMode m) : path(std::move(p)), mode(m) {}
    ~Impl();

    [[noreturn]] void fail(const std::string& reason) const;
    void exec(const char* sql);
    SqliteStatement prepare(const char* sql) const { return SqliteStatement(db, path, sql); }
    std::int64_t pragma(const char* sql) const;
    void require_writable() const;

    void connect(int flags);

    /// First read of the file. A writer killed inside a transaction leaves a hot journal that
    /// SQLite must roll back before anyone reads; a read-only connection cannot, so a short
    /// read-write connection (which never creates the file) restores the last committed state.
    void first_read();

    /// One writer at a time (database_lock.hpp).
    void lock_for_writing();

    void open();

    bool has_table(const char* name) const;

    /// See Database::content_fingerprint().
    std::string fingerprint(std::int64_t kind_id) const;

    /// The fingerprint stored with the weights of `kind_id`; empty when there is none.
    std::string weights_basis(std::int64_t kind_id) const;

    void check_schema();
    void create_schema();

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

    std::vector<DescriptorKind> kinds() const;

    /// The kind named `name`, or the only stored kind when `name` is empty, with its row id.
    std::pair<std::int64_t, DescriptorKind> kind(const std::string& name) const;

    /// Stored models with their row ids, by (category, name).
    std::vector<std::pair<std::int64_t, ModelInfo>> models() const;

    std::optional<std::int64_t> model_id(const std::string& category,
                                         const std::string& name) const;
};

}  // namespace esf
