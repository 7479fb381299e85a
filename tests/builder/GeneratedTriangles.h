#pragma once

// The triangles a generator spec makes for its first prototype, for builder tests that start from
// a generated surface rather than a scene file.

#include "RecordingSink.h"

#include <ff/builder/Generators.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace ff::builder::testing {

inline std::vector<storage::PackedTriangle> generatedTriangles(const std::string& spec) {
    auto parsed = parseGeneratorSpec(spec);
    EXPECT_TRUE(parsed.isOk()) << spec;
    if (!parsed.isOk())
        return {};
    RecordingSink sink;
    const auto report = runGenerator(*parsed, sink);
    EXPECT_TRUE(report.isOk()) << report.status().toString();
    return sink.prototypes().empty() ? std::vector<storage::PackedTriangle>{}
                                     : sink.prototypes()[0].triangles;
}

} // namespace ff::builder::testing
