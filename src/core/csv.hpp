#pragma once
// The one CSV reader of esf (test sets, scene sets, catalogs): RFC 4180 records, a UTF-8 byte
// order mark skipped, LF or CRLF line ends, blank lines dropped.

#include <cstddef>
#include <string>
#include <vector>

namespace esf::detail {

struct CsvRecord {
    std::size_t line = 0;  ///< 1-based line where the record starts
    std::vector<std::string> fields;
};

/// Records of `text`; throws esf::IoError "path:line: reason" for an unterminated quote or text
/// after a closing quote.
std::vector<CsvRecord> parse_csv(const std::string& text, const std::string& path);

/// Leading and trailing white space removed.
std::string trim(const std::string& s);
/// ASCII lower case.
std::string lower(std::string s);

/// Index of the header field named `name` (case-insensitive, spaces trimmed), or
/// header.fields.size() when there is none.
std::size_t column_of(const CsvRecord& header, const std::string& name);

}  // namespace esf::detail
