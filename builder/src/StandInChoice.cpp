#include "StandInChoice.h"

#include "CellViews.h"
#include "StandInError.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace ff::builder {

StandInMeasure::StandInMeasure(
        std::span<const storage::PackedTriangle> source,
        const glm::vec3& boundsMin,
        const glm::vec3& boundsMax)
    : mSource(source), mMin(boundsMin), mMax(boundsMax) {
    const glm::vec3 extent = boundsMax - boundsMin;
    mSide = std::max({extent.x, extent.y, extent.z});
}

StandInMeasure::~StandInMeasure() = default;

CellViews StandInMeasure::blankViews(int span) const {
    // The cell `span` pixels across, and a pixel of margin on every side, so what bleeds past
    // its bounds is seen.
    const float pixel = mSide / static_cast<float>(span);
    const glm::vec3 lo = mMin - glm::vec3(pixel);
    return CellViews(lo, lo + glm::vec3(pixel * static_cast<float>(span + 2)), span + 2);
}

const CellViews& StandInMeasure::sourceViews(int span) {
    auto found = mSourceViews.find(span);
    if (found == mSourceViews.end()) {
        found = mSourceViews.emplace(span, blankViews(span)).first;
        found->second.drawTriangles(mSource);
    }
    return found->second;
}

ViewDifference StandInMeasure::compareAt(const StandIn& candidate, float candidateError, float viewError) {
    if (!measurable() || !(viewError >= 0.0f) || !std::isfinite(viewError) || !std::isfinite(candidateError))
        return {1.0, 255.0}; // nothing it could be said to match
    // Where a pixel is the view's error, a pixel's shift is what the error allows; drawn finer
    // (a small span, kMinMeasureSpan), the shift it allows is as many pixels as the error spans.
    const float span = viewError > 0.0f ? mSide / viewError : INFINITY;
    const int pixels = static_cast<int>(std::clamp(
            std::ceil(span), static_cast<float>(kMinMeasureSpan), static_cast<float>(kMaxMeasureSpan)));
    const float pixel = mSide / static_cast<float>(pixels);
    const int reach = static_cast<int>(std::clamp(std::floor(viewError / pixel), 1.0f, static_cast<float>(pixels)));
    CellViews views = blankViews(pixels);
    views.drawTriangles(candidate.triangles);
    // The runtime draws a splat twice its error across on screen (no holes).
    views.drawSplats(candidate.points, 2.0f * candidateError);
    return viewDifference(sourceViews(pixels), views, reach, kShadingColourStep);
}

MeasuredStandIn StandInMeasure::measure(const StandIn& candidate) {
    MeasuredStandIn m;
    m.error = candidate.error;
    if (!measurable() || !(m.error >= 0.0f) || !std::isfinite(m.error))
        return m; // no surface to stand in for, or no promise to keep
    // The error at least doubles each round, from at least side / 64: at most 6 more rounds
    // before it passes side / 2.
    while (m.error <= mSide / kMinStandInSpanPixels) {
        const ViewDifference difference = compareAt(candidate, m.error, m.error);
        m.mismatch = difference.mismatch;
        if (m.mismatch <= kMaxStandInMismatch) {
            m.pays = true;
            return m;
        }
        // Below side / 64 it was measured at 64 pixels already: the next round is coarser.
        m.error = std::max(2.0f * m.error, 2.0f * mSide / static_cast<float>(kMaxMeasureSpan));
        ++m.raised;
    }
    return m; // keeps its shape only where the cube is nearly drawn: does not pay
}

bool StandInMeasure::firstIsBetter(
        const StandIn& a, const MeasuredStandIn& aMeasured, const StandIn& b, const MeasuredStandIn& bMeasured) {
    const float both = std::max(aMeasured.error, bMeasured.error); // where both are drawn
    const double da = compareAt(a, aMeasured.error, both).meanDifference;
    const double db = compareAt(b, bMeasured.error, both).meanDifference;
    if (std::abs(da - db) > std::max(kStandInDifferenceTie, 0.1 * std::max(da, db)))
        return da < db;
    return prefer(aMeasured, elementsOf(a), bMeasured, elementsOf(b));
}

bool prefer(const MeasuredStandIn& a, std::size_t aElements, const MeasuredStandIn& b, std::size_t bElements) {
    if (a.error * kStandInErrorTie < b.error)
        return true;
    if (b.error * kStandInErrorTie < a.error)
        return false;
    return aElements <= bElements;
}

std::size_t elementsOf(const StandIn& standIn) noexcept {
    return standIn.triangles.size() + standIn.points.size();
}

} // namespace ff::builder
