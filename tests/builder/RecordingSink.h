#pragma once

// A test fake behind ISceneSink: records every prototype, triangle batch and instance in memory.

#include <ff/builder/SceneSink.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ff::builder::testing {

class RecordingSink final : public ISceneSink {
public:
    struct Prototype {
        std::string name;
        std::vector<storage::PackedTriangle> triangles;
    };
    struct Instance {
        PrototypeId prototype = 0;
        glm::mat4 transform{1.0f};
    };

    Result<PrototypeId> addPrototype(std::string_view name) override {
        mPrototypes.push_back({std::string(name), {}});
        return static_cast<PrototypeId>(mPrototypes.size() - 1);
    }

    Status addTriangles(
            PrototypeId prototype, std::span<const storage::PackedTriangle> triangles) override {
        if (prototype >= mPrototypes.size())
            return {ErrorCode::InvalidArgument, "unknown prototype"};
        auto& out = mPrototypes[prototype].triangles;
        out.insert(out.end(), triangles.begin(), triangles.end());
        mLargestBatch = std::max(mLargestBatch, triangles.size());
        ++mBatches;
        return Status::ok();
    }

    Status addInstance(PrototypeId prototype, const glm::dmat4& transform) override {
        if (prototype >= mPrototypes.size())
            return {ErrorCode::InvalidArgument, "unknown prototype"};
        mInstances.push_back({prototype, glm::mat4(transform)});
        return Status::ok();
    }

    Status declareVoxelGrid(PrototypeId prototype, const VoxelGrid& grid) override {
        if (prototype >= mPrototypes.size())
            return {ErrorCode::InvalidArgument, "unknown prototype"};
        mVoxelGrids.emplace_back(prototype, grid);
        return Status::ok();
    }

    const std::vector<Prototype>& prototypes() const { return mPrototypes; }
    const std::vector<std::pair<PrototypeId, VoxelGrid>>& voxelGrids() const { return mVoxelGrids; }
    const std::vector<Instance>& instances() const { return mInstances; }
    std::size_t largestBatch() const { return mLargestBatch; }
    std::size_t batches() const { return mBatches; }

    std::uint64_t storedTriangles() const {
        std::uint64_t n = 0;
        for (const Prototype& p : mPrototypes)
            n += p.triangles.size();
        return n;
    }

    std::size_t instancesOf(PrototypeId prototype) const {
        return static_cast<std::size_t>(
                std::count_if(mInstances.begin(), mInstances.end(), [&](const Instance& i) {
                    return i.prototype == prototype;
                }));
    }

private:
    std::vector<Prototype> mPrototypes;
    std::vector<Instance> mInstances;
    std::vector<std::pair<PrototypeId, VoxelGrid>> mVoxelGrids;
    std::size_t mLargestBatch = 0;
    std::size_t mBatches = 0;
};

} // namespace ff::builder::testing
