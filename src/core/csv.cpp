#include "core/csv.hpp"

#include <cctype>

#include "esf/core/error.hpp"

namespace esf::detail {

std::vector<CsvRecord> parse_csv(const std::string& text, const std::string& path) {
    std::vector<CsvRecord> records;
    const std::size_t n = text.size();
    std::size_t i = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;  // UTF-8 byte order mark
    std::size_t line = 1;
    while (i < n) {
        CsvRecord record;
        record.line = line;
        std::string field;
        bool quoted = false, any_quote = false;
        for (;;) {
            if (i < n && text[i] == '"' && field.empty() && !quoted) {
                quoted = any_quote = true;
                const std::size_t start = line;
                ++i;
                for (;;) {
                    if (i >= n)
                        throw IoError(file_message(path, start, "unterminated quoted field"));
                    const char c = text[i++];
                    if (c == '"') {
                        if (i < n && text[i] == '"') {
                            field += '"';
                            ++i;
                        } else {
                            break;
                        }
                    } else {
                        if (c == '\n') ++line;
                        field += c;
                    }
                }
                continue;
            }
            const bool crlf = i + 1 < n && text[i] == '\r' && text[i + 1] == '\n';
            if (i >= n || text[i] == '\n' || crlf) {
                record.fields.push_back(std::move(field));
                if (i < n) {
                    i += crlf ? 2 : 1;
                    ++line;
                }
                break;
            }
            if (text[i] == ',') {
                record.fields.push_back(std::move(field));
                field.clear();
                quoted = false;
                ++i;
                continue;
            }
            if (quoted)
                throw IoError(file_message(path, line, "text after the closing quote of a field"));
            field += text[i++];
        }
        const bool blank = record.fields.size() == 1 && record.fields[0].empty() && !any_quote;
        if (!blank) records.push_back(std::move(record));
    }
    return records;
}

std::string trim(const std::string& s) {
    std::size_t b = 0, e = s.size();
    while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
    while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
    return s.substr(b, e - b);
}

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::size_t column_of(const CsvRecord& header, const std::string& name) {
    for (std::size_t c = 0; c < header.fields.size(); ++c)
        if (lower(trim(header.fields[c])) == name) return c;
    return header.fields.size();
}

}  // namespace esf::detail
