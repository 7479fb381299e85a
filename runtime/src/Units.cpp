#include <ff/runtime/Units.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

namespace ff::runtime {

namespace {

/** 'text', built by appending: GCC 12 reports a false -Wrestrict (its bug 105329) for
 *  "'" + std::string(text) + "'" once inlined into these parsers. */
std::string quoted(std::string_view text) {
    std::string out;
    out.reserve(text.size() + 2);
    out += '\'';
    out += text;
    out += '\'';
    return out;
}

Result<double> parseNumber(std::string_view text, std::string_view what) {
    double value = 0.0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
        return Status(ErrorCode::InvalidArgument, std::string(what) + ": " + quoted(text) + " is not a number");
    return value;
}

} // namespace

Result<std::uint64_t> parseByteSize(std::string_view text) {
    std::size_t split = 0;
    while (split < text.size() && (std::isdigit(static_cast<unsigned char>(text[split])) || text[split] == '.'))
        ++split;
    const std::string_view digits = text.substr(0, split);
    std::string unit(text.substr(split));
    for (char& c : unit)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    double scale = 0.0;
    if (unit.empty() || unit == "b")
        scale = 1.0;
    else if (unit == "k" || unit == "kib" || unit == "kb")
        scale = 1024.0;
    else if (unit == "m" || unit == "mib" || unit == "mb")
        scale = 1024.0 * 1024.0;
    else if (unit == "g" || unit == "gib" || unit == "gb")
        scale = 1024.0 * 1024.0 * 1024.0;
    else if (unit == "t" || unit == "tib" || unit == "tb")
        scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
    if (digits.empty() || scale == 0.0)
        return Status(ErrorCode::InvalidArgument, quoted(text) + " is not a size (try 512MiB or 2GiB)");
    FF_ASSIGN_OR_RETURN(const double value, parseNumber(digits, "size"));
    return static_cast<std::uint64_t>(std::llround(value * scale));
}

Result<glm::ivec2> parseImageSize(std::string_view text) {
    const std::size_t x = text.find('x');
    if (x == std::string_view::npos)
        return Status(ErrorCode::InvalidArgument, "image size " + quoted(text) + " must look like 640x480");
    FF_ASSIGN_OR_RETURN(const double w, parseNumber(text.substr(0, x), "image width"));
    FF_ASSIGN_OR_RETURN(const double h, parseNumber(text.substr(x + 1), "image height"));
    if (w < 1 || h < 1 || w > 16384 || h > 16384 || w != std::floor(w) || h != std::floor(h))
        return Status(ErrorCode::InvalidArgument, "image size " + quoted(text) + " must be whole pixels in 1..16384");
    return glm::ivec2(static_cast<int>(w), static_cast<int>(h));
}

Result<glm::vec3> parseVec3(std::string_view text) {
    FF_ASSIGN_OR_RETURN(const glm::dvec3 v, parseDVec3(text));
    return glm::vec3(v);
}

Result<glm::dvec3> parseDVec3(std::string_view text) {
    glm::dvec3 v(0.0);
    std::size_t start = 0;
    for (int i = 0; i < 3; ++i) {
        const std::size_t comma = i < 2 ? text.find(',', start) : text.size();
        if (comma == std::string_view::npos)
            return Status(ErrorCode::InvalidArgument, quoted(text) + " must be three numbers: x,y,z");
        FF_ASSIGN_OR_RETURN(const double c, parseNumber(text.substr(start, comma - start), "vector"));
        v[i] = c;
        start = comma + 1;
    }
    return v;
}

std::string formatBytes(std::uint64_t bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    double value = static_cast<double>(bytes);
    int unit = 0;
    while (value >= 1024.0 && unit < 4) {
        value /= 1024.0;
        ++unit;
    }
    char text[32];
    std::snprintf(text, sizeof(text), unit == 0 ? "%.0f %s" : "%.1f %s", value, units[unit]);
    return text;
}

} // namespace ff::runtime
