#pragma once

// A do-nothing renderer for traversal tests: keeps what every batch of a frame held (cubes and
// geometry runs in arrival order, each with its transform's matrix) and the largest batch.

#include <ff/runtime/Traversal.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace ff::runtime::test {

struct RecordedCube {
    CubeDraw cube;
    glm::mat4 transform;
};

struct RecordedRun {
    GeometryDraw run;
    glm::mat4 transform;
};

class RecordingSink final : public IDrawSink {
public:
    /** keep = false counts without keeping (a cut too large to hold). */
    explicit RecordingSink(bool keep = true)
        : mKeep(keep) {}

    Status draw(const DrawList& batch, FrameStats&) override {
        ++batches;
        maxBatchBytes = std::max(maxBatchBytes, batch.bytes());
        cubeCount += batch.cubes.size();
        runCount += batch.geometry.size();
        if (!batch.geometry.empty() && cubeCount > batch.cubes.size())
            geometryAfterCubes = true; // a cube was drawn before this geometry
        for (const CubeDraw& c : batch.cubes) {
            if (!batch.cubesAsPoints)
                cubesAsFaces = true;
            if (mKeep)
                cubes.push_back({c, batch.transforms.at(c.transform)});
        }
        if (mKeep) {
            for (const GeometryDraw& g : batch.geometry)
                runs.push_back({g, batch.transforms.at(g.transform)});
        }
        return Status::ok();
    }

    std::vector<RecordedCube> cubes;
    std::vector<RecordedRun> runs;
    std::size_t batches = 0;
    std::size_t maxBatchBytes = 0;
    std::size_t cubeCount = 0;
    std::size_t runCount = 0;
    bool geometryAfterCubes = false;
    bool cubesAsFaces = false;

private:
    bool mKeep;
};

} // namespace ff::runtime::test
