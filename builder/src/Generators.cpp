// Spec parsing, the catalog and dispatch for the procedural generators. Each generator lives
// in its own file under generators/; this file only knows their names.

#include "generators/GeneratorKit.h"

#include <ff/builder/Generators.h>

#include <algorithm>
#include <string>

namespace ff::builder {

namespace {

bool isNameChar(char c) noexcept {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-';
}

bool isName(std::string_view text) noexcept {
    return !text.empty() && std::all_of(text.begin(), text.end(), isNameChar);
}

Status badSpec(std::string_view text, const std::string& why) {
    return Status(
            ErrorCode::InvalidArgument,
            "generator spec '" + std::string(text) + "': " + why +
                    " (expected NAME[:key=value,...], e.g. forest:trees=16,seed=3)");
}

const std::vector<generators::GeneratorEntry>& registry() {
    // Built once, immutable afterwards: safe to share between threads.
    static const std::vector<generators::GeneratorEntry> kEntries = {
            generators::forestGenerator(),
            generators::terrainGenerator(),
            generators::moleculeGenerator(),
            generators::blindsGenerator(),
            generators::sphereGenerator(),
            generators::cityGenerator(),
            generators::cathedralGenerator(),
            generators::isosurfaceGenerator(),
    };
    return kEntries;
}

} // namespace

Result<GeneratorSpec> parseGeneratorSpec(std::string_view text) {
    GeneratorSpec spec;
    const std::size_t colon = text.find(':');
    const std::string_view name = text.substr(0, colon);
    if (!isName(name))
        return badSpec(
                text, "generator name '" + std::string(name) + "' is empty or not [A-Za-z0-9_-]");
    spec.name = std::string(name);
    if (colon == std::string_view::npos)
        return spec;

    std::string_view rest = text.substr(colon + 1);
    while (true) {
        const std::size_t comma = rest.find(',');
        const std::string_view item = rest.substr(0, comma);
        const std::size_t equals = item.find('=');
        if (equals == std::string_view::npos)
            return badSpec(text, "parameter '" + std::string(item) + "' is not key=value");
        const std::string_view key = item.substr(0, equals);
        const std::string_view value = item.substr(equals + 1);
        if (!isName(key))
            return badSpec(
                    text, "parameter key '" + std::string(key) + "' is empty or not [A-Za-z0-9_-]");
        if (value.empty())
            return badSpec(text, "parameter '" + std::string(key) + "' has an empty value");
        if (!spec.params.emplace(std::string(key), std::string(value)).second)
            return badSpec(text, "parameter '" + std::string(key) + "' is given twice");
        if (comma == std::string_view::npos)
            break;
        rest = rest.substr(comma + 1);
    }
    return spec;
}

const std::vector<GeneratorInfo>& generatorCatalog() {
    static const std::vector<GeneratorInfo> kCatalog = [] {
        std::vector<GeneratorInfo> catalog;
        for (const generators::GeneratorEntry& entry : registry())
            catalog.push_back(entry.info);
        return catalog;
    }();
    return kCatalog;
}

Result<GeneratorReport> runGenerator(const GeneratorSpec& spec, ISceneSink& sink) {
    std::string known;
    for (const generators::GeneratorEntry& entry : registry()) {
        if (entry.info.name == spec.name)
            return entry.run(spec, sink);
        known.append(known.empty() ? "" : ", ").append(entry.info.name);
    }
    return Status(
            ErrorCode::InvalidArgument,
            "unknown generator '" + spec.name + "' (known: " + known + ")");
}

} // namespace ff::builder
