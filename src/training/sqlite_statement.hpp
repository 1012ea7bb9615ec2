#pragma once
// A thin RAII layer over one prepared SQLite statement: every failure becomes an esf::IoError
// naming the database file.

#include <sqlite3.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace esf::detail {

/// The bytes of `values` as stored in a blob (float32, this host's byte order: little endian).
std::vector<unsigned char> float_blob(std::span<const float> values);

class SqliteStatement {
  public:
    /// Prepares `sql` on `db`; `path` (the database file, named in errors) must outlive it.
    SqliteStatement(sqlite3* db, const std::string& path, const char* sql);
    ~SqliteStatement();
    SqliteStatement(const SqliteStatement&) = delete;
    SqliteStatement& operator=(const SqliteStatement&) = delete;

    SqliteStatement& bind(int i, std::int64_t v) { return check(sqlite3_bind_int64(stmt_, i, v)); }
    SqliteStatement& bind(int i, int v) { return bind(i, std::int64_t{v}); }
    SqliteStatement& bind(int i, std::size_t v) { return bind(i, static_cast<std::int64_t>(v)); }
    SqliteStatement& bind(int i, double v) { return check(sqlite3_bind_double(stmt_, i, v)); }
    SqliteStatement& bind(int i, const std::string& v) {
        return check(
            sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
    }
    SqliteStatement& bind(int i, const char* v) { return bind(i, std::string(v)); }
    SqliteStatement& bind_blob(int i, std::span<const float> v);

    /// Steps once; true while a row is available.
    bool step();
    /// Steps to the end, then resets the statement and its bindings.
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
    std::string text(int col) const;
    int type(int col) const { return sqlite3_column_type(stmt_, col); }
    /// Copies a float32 blob of exactly `count` values into `out`; `what` names it in the error
    /// for a blob of another size.
    void floats(int col, float* out, std::size_t count, const char* what) const;
    std::vector<float> floats(int col) const;

  private:
    SqliteStatement& check(int rc) {
        if (rc != SQLITE_OK) fail();
        return *this;
    }
    [[noreturn]] void fail() const;

    sqlite3* db_;
    const std::string* path_;
    sqlite3_stmt* stmt_ = nullptr;
};

}  // namespace esf::detail
