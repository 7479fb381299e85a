#pragma once

// Scenario files: what `farfield bench` runs. A scenario is a JSON file (bench/NAME.json) naming
// a benchmark kind and its parameters; the format is documented in bench/README.md.
//
//   findScenario(name or path) ──▶ loadScenario(file, quick) ──▶ Scenario ──▶ ScenarioReader
//                                   (applies "quick" as a JSON merge patch)    (typed reads;
//                                   unknown
//                                                                               keys are errors)

#include <ff/storage/Status.h>

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace ff::bench {

/** One scenario file, read, with its "quick" overrides applied or not. */
struct Scenario {
    std::filesystem::path file; ///< as found (relative paths stay relative)
    std::string name;           ///< output prefix (OUT/NAME.csv ...): "name", else the file's stem
    std::string title;          ///< "title", else the name
    std::string description;    ///< "description", else empty
    std::string kind;           ///< table2, forest, build, paging, views, path
    bool quick = false;         ///< whether "quick" was applied
    /** The file's object after the quick merge: what the kind reads through reader(). */
    nlohmann::json json;

    /** "bench/x.json" or "bench/x.json (with its quick overrides)", for messages. */
    std::string where() const;
};

/** Scenario kinds `farfield bench` knows, from the one table of kinds (src/Kinds.cpp). */
std::vector<std::string> scenarioKinds();

/**
 * Finds a scenario: an existing file path as given, or a bare name (no '/', no ".json") resolved
 * as bench/NAME.json in the current directory. NotFound names what was tried and lists the
 * scenarios there are.
 */
[[nodiscard]] Result<std::filesystem::path> findScenario(const std::string& nameOrPath);

/** The *.json files of `folder`, sorted by name; empty if there is no such folder. */
std::vector<std::filesystem::path> listScenarioFiles(const std::filesystem::path& folder = "bench");

/**
 * Reads and checks the common keys of a scenario file; with `quick`, applies its "quick" object
 * first as a JSON merge patch (RFC 7386: objects merge key by key, anything else replaces).
 * Errors (InvalidArgument, NotFound) name the file and the key.
 */
[[nodiscard]] Result<Scenario> loadScenario(const std::filesystem::path& file, bool quick);

/**
 * The shared data folder ${shared} stands for, first found of: $FF_SHARED_DATA (an explicit
 * choice wins), the build's FF_SHARED_DATA_DIR, ../shared/data from the current directory.
 */
[[nodiscard]] Result<std::filesystem::path> sharedDataDir();

/** Replaces every "${shared}" in `text` with sharedDataDir(); text without it is returned as is. */
[[nodiscard]] Result<std::string> expandShared(const std::string& text);

/**
 * Typed, checked reads of a scenario's JSON objects. Every read names the key it knows, so
 * finish() can reject keys nobody asked for (a typo would otherwise silently run the default).
 * Reads never throw: a missing key gives the fallback, a wrong type records an error (the first
 * one is kept) and gives the fallback. Readers for nested objects share the error state of the
 * reader they came from; finish() on any of them checks them all.
 */
class ScenarioReader {
public:
    /** Reads `object`, which must outlive the reader; `where` names the file for messages. */
    ScenarioReader(const nlohmann::json& object, std::string where);

    bool has(const char* key);
    double number(const char* key, double fallback);
    bool boolean(const char* key, bool fallback);
    std::int64_t integer(const char* key, std::int64_t fallback);
    std::string string(const char* key, std::string fallback);
    /** A string that must be one of `choices`. */
    std::string
    choice(const char* key, std::string fallback, const std::vector<std::string>& choices);
    std::vector<double> numbers(const char* key, std::vector<double> fallback);
    std::vector<std::string> strings(const char* key, std::vector<std::string> fallback);
    /** A non-empty, increasing list of whole numbers >= 1 (scene-size ladders). */
    std::vector<std::int64_t> ladder(const char* key, std::vector<std::int64_t> fallback);
    /** [width, height], both in 1..16384. */
    std::array<int, 2> size(const char* key, std::array<int, 2> fallback);
    /** A non-empty array of [width, height]. */
    std::vector<std::array<int, 2>>
    sizes(const char* key, std::vector<std::array<int, 2>> fallback);
    /** A nested object; missing reads as {}. */
    ScenarioReader object(const char* key);
    /** An array of objects; missing reads as []. */
    std::vector<ScenarioReader> objects(const char* key);
    /** The value as is (nullptr if missing), for values of more than one type. */
    const nlohmann::json* raw(const char* key);

    /** Records an error about `key` of this object (e.g. a value out of range). */
    void fail(const std::string& key, const std::string& message);
    /** "views[0].camera", or "" at the top. */
    const std::string& path() const noexcept { return mPath; }

    /** The first error recorded so far (unknown keys not checked). */
    [[nodiscard]] const Status& firstError() const noexcept { return mState->firstError; }
    /** The first error recorded by this reader or any reader sharing its state; else unknown
     *  keys (with the keys known there); else ok. */
    [[nodiscard]] Status finish() const;

private:
    struct Seen {
        const nlohmann::json* object;
        std::string path;
        std::set<std::string> known;
    };
    struct State {
        std::string where;
        Status firstError;
        std::deque<Seen> objects; ///< deque: references stay valid as it grows
    };
    ScenarioReader(State& state, const nlohmann::json& object, std::string path);
    const nlohmann::json* lookUp(const char* key);
    std::string keyPath(const std::string& key) const;

    std::unique_ptr<State> mOwnedState; ///< the root reader's; nested readers borrow it
    State* mState = nullptr;
    std::size_t mIndex = 0; ///< this object's entry in mState->objects
    std::string mPath;
};

/** A reader of the scenario's keys, the common ones (name, title, ...) already known. The
 *  scenario must outlive it. */
ScenarioReader readScenario(const Scenario& scenario);

} // namespace ff::bench
