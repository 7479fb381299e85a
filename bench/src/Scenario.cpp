#include <ff/bench/Scenario.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace ff::bench {

namespace {

/** Short rendering of a JSON value for messages. */
std::string shown(const nlohmann::json& value) {
    std::string text = value.dump();
    if (text.size() > 40)
        text = text.substr(0, 37) + "...";
    return text;
}

std::string joined(const std::vector<std::string>& items) {
    std::string text;
    for (const std::string& item : items)
        text += (text.empty() ? "" : ", ") + item;
    return text;
}

bool isSafeName(const std::string& name) {
    return !name.empty() && name.front() != '.' &&
           std::all_of(name.begin(), name.end(), [](char c) {
               return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ||
                      c == '.';
           });
}

std::vector<std::string> availableNames() {
    std::vector<std::string> names;
    for (const std::filesystem::path& file : listScenarioFiles())
        names.push_back(file.stem().string());
    return names;
}

} // namespace

std::string Scenario::where() const {
    return file.string() + (quick ? " (with its quick overrides)" : "");
}

std::vector<std::filesystem::path> listScenarioFiles(const std::filesystem::path& folder) {
    std::vector<std::filesystem::path> files;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(folder, error))
        if (entry.is_regular_file() && entry.path().extension() == ".json")
            files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    return files;
}

Result<std::filesystem::path> findScenario(const std::string& nameOrPath) {
    const bool bareName = nameOrPath.find('/') == std::string::npos &&
                          std::filesystem::path(nameOrPath).extension() != ".json";
    const std::filesystem::path file =
            bareName ? std::filesystem::path("bench") / (nameOrPath + ".json")
                     : std::filesystem::path(nameOrPath);
    if (std::filesystem::is_regular_file(file))
        return file;
    const std::vector<std::string> names = availableNames();
    std::string message = "scenario \"" + nameOrPath + "\" not found: no file " + file.string();
    if (bareName)
        message += " (bare names are looked up in bench/ under the current directory " +
                   std::filesystem::current_path().string() + ")";
    message += names.empty() ? "; there is no bench/ folder with scenarios here (run from the "
                               "repository root, "
                               "or give the path of a scenario file)"
                             : "; available: " + joined(names);
    return Status(ErrorCode::NotFound, message);
}

Result<Scenario> loadScenario(const std::filesystem::path& file, bool quick) {
    std::ifstream in(file, std::ios::binary);
    if (!in)
        return Status(ErrorCode::NotFound, file.string() + ": cannot open the scenario file");
    std::ostringstream text;
    text << in.rdbuf();
    Scenario scenario;
    scenario.file = file;
    scenario.quick = quick;
    try {
        scenario.json = nlohmann::json::parse(text.str(), nullptr, true, /*ignore_comments=*/true);
    } catch (const nlohmann::json::parse_error& e) {
        return Status(ErrorCode::InvalidArgument, file.string() + ": not valid JSON: " + e.what());
    }
    if (!scenario.json.is_object())
        return Status(ErrorCode::InvalidArgument, file.string() + ": a scenario is a JSON object");
    if (quick && scenario.json.contains("quick")) {
        const nlohmann::json overrides = scenario.json["quick"];
        if (!overrides.is_object())
            return Status(
                    ErrorCode::InvalidArgument,
                    file.string() + ": \"quick\" must be an object of overrides");
        for (const char* key : {"name", "kind", "quick"})
            if (overrides.contains(key))
                return Status(
                        ErrorCode::InvalidArgument,
                        file.string() + ": quick." + key +
                                ": the quick overrides cannot change \"" + key + "\"");
        scenario.json.merge_patch(overrides);
    }

    ScenarioReader reader(scenario.json, scenario.where());
    scenario.name = reader.string("name", file.stem().string());
    scenario.title = reader.string("title", scenario.name);
    scenario.description = reader.string("description", "");
    scenario.kind = reader.string("kind", "");
    if (!reader.has("kind"))
        reader.fail(
                "kind",
                std::string("missing; one of ") +
                        joined(scenarioKinds()));
    else
        reader.choice("kind", "", scenarioKinds());
    if (!isSafeName(scenario.name))
        reader.fail(
                "name",
                "\"" + scenario.name +
                        "\" cannot name output files (letters, digits, '-', '_', '.')");
    if (reader.has("quick") && !reader.raw("quick")->is_object())
        reader.fail("quick", "must be an object of overrides");
    // Only the common keys here: the kind reads the rest and rejects unknown keys.
    FF_RETURN_IF_ERROR(reader.firstError());
    return scenario;
}

Result<std::filesystem::path> sharedDataDir() {
    std::vector<std::filesystem::path> tried;
    if (const char* env = std::getenv("FF_SHARED_DATA"); env && *env) {
        if (std::filesystem::is_directory(env))
            return std::filesystem::path(env);
        tried.push_back(std::string("$FF_SHARED_DATA=") + env);
    }
#ifdef FF_SHARED_DATA_DIR
    if (std::filesystem::is_directory(FF_SHARED_DATA_DIR))
        return std::filesystem::path(FF_SHARED_DATA_DIR);
    tried.push_back(FF_SHARED_DATA_DIR);
#endif
    if (std::filesystem::is_directory("../shared/data"))
        return std::filesystem::absolute("../shared/data").lexically_normal();
    tried.push_back("../shared/data");
    std::string list;
    for (const auto& t : tried)
        list += (list.empty() ? "" : ", ") + t.string();
    return Status(
            ErrorCode::NotFound,
            "${shared}: no shared data folder (tried " + list + "); set FF_SHARED_DATA");
}

Result<std::string> expandShared(const std::string& text) {
    static constexpr std::string_view kToken = "${shared}";
    std::string::size_type at = text.find(kToken);
    if (at == std::string::npos)
        return text;
    FF_ASSIGN_OR_RETURN(const std::filesystem::path shared, sharedDataDir());
    std::string result = text;
    for (; at != std::string::npos; at = result.find(kToken, at)) {
        result.replace(at, kToken.size(), shared.string());
        at += shared.string().size();
    }
    return result;
}

// ---- ScenarioReader ----------------------------------------------------------------------

ScenarioReader::ScenarioReader(const nlohmann::json& object, std::string where)
    : mOwnedState(std::make_unique<State>())
    , mState(mOwnedState.get()) {
    mState->where = std::move(where);
    mState->objects.push_back({&object, "", {}});
    mIndex = 0;
    if (!object.is_object())
        fail("", "expected a JSON object, got " + shown(object));
}

ScenarioReader::ScenarioReader(State& state, const nlohmann::json& object, std::string path)
    : mState(&state)
    , mIndex(state.objects.size())
    , mPath(std::move(path)) {
    mState->objects.push_back({&object, mPath, {}});
}

std::string ScenarioReader::keyPath(const std::string& key) const {
    if (mPath.empty())
        return key;
    return key.empty() ? mPath : mPath + "." + key;
}

void ScenarioReader::fail(const std::string& key, const std::string& message) {
    if (!mState->firstError) // keep the first
        return;
    const std::string at = keyPath(key);
    mState->firstError =
            Status(ErrorCode::InvalidArgument,
                   mState->where + ": " + (at.empty() ? "" : at + ": ") + message);
}

const nlohmann::json* ScenarioReader::lookUp(const char* key) {
    Seen& seen = mState->objects[mIndex];
    seen.known.insert(key);
    if (!seen.object->is_object())
        return nullptr;
    const auto it = seen.object->find(key);
    return it == seen.object->end() ? nullptr : &*it;
}

bool ScenarioReader::has(const char* key) {
    return lookUp(key) != nullptr;
}

const nlohmann::json* ScenarioReader::raw(const char* key) {
    return lookUp(key);
}

double ScenarioReader::number(const char* key, double fallback) {
    const nlohmann::json* value = lookUp(key);
    if (!value)
        return fallback;
    if (!value->is_number()) {
        fail(key, "expected a number, got " + shown(*value));
        return fallback;
    }
    return value->get<double>();
}

bool ScenarioReader::boolean(const char* key, bool fallback) {
    const nlohmann::json* value = lookUp(key);
    if (!value)
        return fallback;
    if (!value->is_boolean()) {
        fail(key, "expected true or false, got " + shown(*value));
        return fallback;
    }
    return value->get<bool>();
}

std::int64_t ScenarioReader::integer(const char* key, std::int64_t fallback) {
    const nlohmann::json* value = lookUp(key);
    if (!value)
        return fallback;
    if (value->is_number_integer())
        return value->get<std::int64_t>();
    // 1e6 is a float in JSON; accept it when it is a whole number.
    if (value->is_number_float()) {
        const double d = value->get<double>();
        if (std::floor(d) == d && std::fabs(d) < 9.0e18)
            return static_cast<std::int64_t>(d);
    }
    fail(key, "expected a whole number, got " + shown(*value));
    return fallback;
}

std::string ScenarioReader::string(const char* key, std::string fallback) {
    const nlohmann::json* value = lookUp(key);
    if (!value)
        return fallback;
    if (!value->is_string()) {
        fail(key, "expected a string, got " + shown(*value));
        return fallback;
    }
    return value->get<std::string>();
}

std::string ScenarioReader::choice(
        const char* key, std::string fallback, const std::vector<std::string>& choices) {
    std::string value = string(key, fallback);
    if (std::find(choices.begin(), choices.end(), value) == choices.end()) {
        fail(key, "\"" + value + "\" is not one of " + joined(choices));
        return fallback;
    }
    return value;
}

std::vector<double> ScenarioReader::numbers(const char* key, std::vector<double> fallback) {
    const nlohmann::json* value = lookUp(key);
    if (!value)
        return fallback;
    std::vector<double> result;
    if (value->is_array())
        for (const nlohmann::json& item : *value)
            if (item.is_number())
                result.push_back(item.get<double>());
    if (!value->is_array() || result.size() != value->size() || result.empty()) {
        fail(key, "expected a non-empty array of numbers, got " + shown(*value));
        return fallback;
    }
    return result;
}

std::vector<std::string>
ScenarioReader::strings(const char* key, std::vector<std::string> fallback) {
    const nlohmann::json* value = lookUp(key);
    if (!value)
        return fallback;
    std::vector<std::string> result;
    if (value->is_array())
        for (const nlohmann::json& item : *value)
            if (item.is_string())
                result.push_back(item.get<std::string>());
    if (!value->is_array() || result.size() != value->size()) {
        fail(key, "expected an array of strings, got " + shown(*value));
        return fallback;
    }
    return result;
}

std::vector<std::int64_t>
ScenarioReader::ladder(const char* key, std::vector<std::int64_t> fallback) {
    if (!has(key))
        return fallback;
    std::vector<std::int64_t> ladder;
    for (const double value : numbers(key, {})) {
        if (!(value >= 1.0 && value < 9.0e18) || std::floor(value) != value ||
            (!ladder.empty() && value <= static_cast<double>(ladder.back()))) {
            fail(key, "must be whole numbers >= 1 in increasing order");
            return fallback;
        }
        ladder.push_back(static_cast<std::int64_t>(value));
    }
    return ladder.empty() ? fallback : ladder;
}

namespace {

bool isImageSize(const nlohmann::json& value) {
    auto side = [](const nlohmann::json& v) {
        return v.is_number_integer() && v.get<std::int64_t>() >= 1 &&
               v.get<std::int64_t>() <= 16384;
    };
    return value.is_array() && value.size() == 2 && side(value[0]) && side(value[1]);
}

} // namespace

std::array<int, 2> ScenarioReader::size(const char* key, std::array<int, 2> fallback) {
    const nlohmann::json* value = lookUp(key);
    if (!value)
        return fallback;
    if (!isImageSize(*value)) {
        fail(key, "expected [width, height] in pixels (1..16384), got " + shown(*value));
        return fallback;
    }
    return {(*value)[0].get<int>(), (*value)[1].get<int>()};
}

std::vector<std::array<int, 2>>
ScenarioReader::sizes(const char* key, std::vector<std::array<int, 2>> fallback) {
    const nlohmann::json* value = lookUp(key);
    if (!value)
        return fallback;
    std::vector<std::array<int, 2>> result;
    if (value->is_array())
        for (const nlohmann::json& item : *value)
            if (isImageSize(item))
                result.push_back({item[0].get<int>(), item[1].get<int>()});
    if (!value->is_array() || result.empty() || result.size() != value->size()) {
        fail(key, "expected a non-empty array of [width, height] (1..16384), got " + shown(*value));
        return fallback;
    }
    return result;
}

ScenarioReader ScenarioReader::object(const char* key) {
    static const nlohmann::json kEmpty = nlohmann::json::object();
    const nlohmann::json* value = lookUp(key);
    if (value && !value->is_object())
        fail(key, "expected an object, got " + shown(*value));
    return ScenarioReader(*mState, value && value->is_object() ? *value : kEmpty, keyPath(key));
}

std::vector<ScenarioReader> ScenarioReader::objects(const char* key) {
    std::vector<ScenarioReader> result;
    const nlohmann::json* value = lookUp(key);
    if (!value)
        return result;
    if (!value->is_array()) {
        fail(key, "expected an array of objects, got " + shown(*value));
        return result;
    }
    for (std::size_t i = 0; i < value->size(); ++i) {
        const std::string path = keyPath(key) + "[" + std::to_string(i) + "]";
        if (!(*value)[i].is_object()) {
            fail(std::string(key) + "[" + std::to_string(i) + "]",
                 "expected an object, got " + shown((*value)[i]));
            continue;
        }
        result.push_back(ScenarioReader(*mState, (*value)[i], path));
    }
    return result;
}

Status ScenarioReader::finish() const {
    if (!mState->firstError)
        return mState->firstError;
    for (const Seen& seen : mState->objects) {
        if (!seen.object->is_object())
            continue;
        for (const auto& [key, value] : seen.object->items()) {
            if (seen.known.count(key))
                continue;
            const std::vector<std::string> known(seen.known.begin(), seen.known.end());
            return Status(
                    ErrorCode::InvalidArgument,
                    mState->where + ": " + (seen.path.empty() ? "" : seen.path + ": ") +
                            "unknown key \"" + key + "\" (known here: " + joined(known) + ")");
        }
    }
    return Status::ok();
}

ScenarioReader readScenario(const Scenario& scenario) {
    ScenarioReader reader(scenario.json, scenario.where());
    for (const char* key : {"name", "title", "description", "kind", "quick"})
        (void)reader.has(key);
    return reader;
}

} // namespace ff::bench
