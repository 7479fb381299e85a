#pragma once

// A fake ISceneSink for generator tests: counts and summarises what a source pushes (per
// prototype bounds, batch sizes, a hash of every triangle byte) without keeping the triangles,
// so tests can check large streams in constant memory. Keeps triangles only when asked.

#include <ff/builder/SceneSink.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ff::builder::test {

class CountingSink final : public ISceneSink {
public:
    struct PrototypeStats {
        std::string name;
        std::uint64_t triangles = 0;
        glm::vec3 boundsMin{std::numeric_limits<float>::infinity()};
        glm::vec3 boundsMax{-std::numeric_limits<float>::infinity()};
        float maxRadialXZ = 0.0f; ///< largest distance of a vertex from the Y axis
    };

    struct Instance {
        PrototypeId prototype;
        glm::mat4 transform;
    };

    explicit CountingSink(bool keepTriangles = false)
        : mKeepTriangles(keepTriangles) {}

    /** Makes addTriangles fail with IoError once this many batches have been accepted. */
    void failAfterBatches(std::uint64_t count) { mFailAfterBatches = count; }

    Result<PrototypeId> addPrototype(std::string_view name) override {
        prototypes.push_back(PrototypeStats{std::string(name)});
        return static_cast<PrototypeId>(prototypes.size() - 1);
    }

    Status
    addTriangles(PrototypeId prototype, std::span<const storage::PackedTriangle> batch) override {
        if (prototype >= prototypes.size())
            return Status(ErrorCode::InvalidArgument, "undeclared prototype");
        if (batches >= mFailAfterBatches)
            return Status(ErrorCode::IoError, "injected failure");
        ++batches;
        maxBatch = std::max<std::uint64_t>(maxBatch, batch.size());
        PrototypeStats& stats = prototypes[prototype];
        stats.triangles += batch.size();
        triangleCount += batch.size();
        for (const storage::PackedTriangle& triangle : batch) {
            triangleHash = fnv1a(triangleHash, &triangle, sizeof(triangle));
            std::array<glm::vec3, 3> p;
            for (std::size_t k = 0; k < 3; ++k) {
                const auto& q = triangle.vertices[k].position;
                p[k] = glm::vec3(q[0], q[1], q[2]);
                if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) {
                    ++nonFiniteTriangles;
                    continue;
                }
                stats.boundsMin = glm::min(stats.boundsMin, p[k]);
                stats.boundsMax = glm::max(stats.boundsMax, p[k]);
                stats.maxRadialXZ =
                        std::max(stats.maxRadialXZ, std::sqrt(p[k].x * p[k].x + p[k].z * p[k].z));
            }
            const glm::vec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
            if (!(glm::dot(n, n) > 0.0f))
                ++zeroAreaTriangles;
            if (mKeepTriangles)
                triangles.push_back(triangle);
        }
        return Status::ok();
    }

    Status addInstance(PrototypeId prototype, const glm::dmat4& transform) override {
        if (prototype >= prototypes.size())
            return Status(ErrorCode::InvalidArgument, "undeclared prototype");
        instanceHash = fnv1a(instanceHash, &prototype, sizeof(prototype));
        // Hashed as float, as generators produce them, so the pinned hashes keep their meaning.
        const glm::mat4 single(transform);
        instanceHash = fnv1a(instanceHash, &single, sizeof(single));
        instances.push_back({prototype, single});
        return Status::ok();
    }

    std::vector<PrototypeStats> prototypes;
    std::vector<Instance> instances;
    std::vector<storage::PackedTriangle> triangles; ///< only with keepTriangles
    std::uint64_t triangleCount = 0;
    std::uint64_t batches = 0;
    std::uint64_t maxBatch = 0;
    std::uint64_t nonFiniteTriangles = 0;
    std::uint64_t zeroAreaTriangles = 0;
    std::uint64_t triangleHash = kFnvOffset; ///< FNV-1a 64 of every triangle byte, in order
    std::uint64_t instanceHash = kFnvOffset;

private:
    static constexpr std::uint64_t kFnvOffset = 0xCBF29CE484222325ull;

    static std::uint64_t fnv1a(std::uint64_t hash, const void* data, std::size_t size) {
        const auto* bytes = static_cast<const unsigned char*>(data); // byte view: may alias
        for (std::size_t i = 0; i < size; ++i)
            hash = (hash ^ bytes[i]) * 0x100000001B3ull;
        return hash;
    }

    bool mKeepTriangles;
    std::uint64_t mFailAfterBatches = std::numeric_limits<std::uint64_t>::max();
};

} // namespace ff::builder::test
