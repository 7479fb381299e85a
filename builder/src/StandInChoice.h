#pragma once

// A cell's stand-in chosen by measured error and cost (issue 17, item 4). Each candidate (a
// simplified copy, splats) promises an error: the runtime draws it where that error projects
// below ε pixels, so at ε = 1 it is first drawn where a pixel spans its error. The builder
// checks the promise there: it draws the candidate and its source (what the cell stands for)
// from the cell's six face directions at that size (CellViews.h) and compares coverage and
// shading, allowing the shift its error allows (a pixel there). Where they differ in more than kMaxStandInMismatch of the
// pixels, the candidate keeps its shape only farther away: its error is doubled and measured
// again. A candidate that keeps it only where its cell spans under kMinStandInSpanPixels, about
// where the cell's cube takes over, does not pay and is not kept. Of two candidates that pay,
// the cell keeps the one whose views differ less from the source's where both would be drawn
// (at the larger error; mean difference of shade); where they look alike, the one with the
// smaller measured error (drawn from nearer, so it saves more of the subtree), and where the
// errors are within kStandInErrorTie, the one with fewer elements.
//
// meshoptimizer's quadric error bounds how far the surface moved, not what it shows: a
// simplification that merges leaves or closes a window keeps a small error and loses coverage;
// splats promise a cover radius and bleed past outlines. The measure sees both.

#include "StandIns.h"

#include <glm/vec3.hpp>

#include <cmath>
#include <map>
#include <span>

namespace ff::builder {

class CellViews;
struct ViewDifference;

/** A candidate keeps its error where at most this share of the pixels of its views, drawn a
 *  pixel to its error, differ from its source's (more than a pixel's shift, or kShadingColourStep). */
inline constexpr double kMaxStandInMismatch = 0.05;
/** A candidate must keep its shape from where its cell spans at least this many pixels (its
 *  measured error at most 1/this of the cell's largest side): the cube is drawn below about
 *  ε pixels, the candidate where its error is below ε, so it is drawn over at least this
 *  factor of distances before the cube takes over. */
inline constexpr float kMinStandInSpanPixels = 2.0f;
/** Views are drawn with the cell at least this many pixels across: a cell first drawn a few
 *  pixels across is measured finer, with the shift its error allows in as many pixels (a view
 *  of a few pixels would count a pixel's quantisation as a tenth of the image). */
inline constexpr int kMinMeasureSpan = 16;
/** Views are drawn with the cell at most this many pixels across (a candidate whose error is
 *  a smaller share of its cell is measured a little coarser than where it is first drawn). */
inline constexpr int kMaxMeasureSpan = 64;
/** Candidates whose mean differences from their source, where both are drawn, are within
 *  this many 8-bit steps (or a tenth) of each other look alike: the error decides. */
inline constexpr double kStandInDifferenceTie = 0.5;
/** Errors within this factor of each other count as equal: the cheaper candidate is kept. */
inline constexpr float kStandInErrorTie = 1.25f;

/** A candidate as measured. */
struct MeasuredStandIn {
    float error = 0.0f;     ///< the error it keeps (its own, doubled `raised` times)
    double mismatch = 0.0;  ///< its views' share of differing pixels at that error
    int raised = 0;         ///< how many times its error was doubled
    bool pays = false;      ///< keeps its shape where its cell spans kMinStandInSpanPixels or more
};

/** Measures candidates against one source (the source's views drawn once per resolution). */
class StandInMeasure {
public:
    /** `source` (borrowed) inside the box [boundsMin, boundsMax]. */
    StandInMeasure(
            std::span<const storage::PackedTriangle> source,
            const glm::vec3& boundsMin,
            const glm::vec3& boundsMax);
    ~StandInMeasure();
    StandInMeasure(const StandInMeasure&) = delete;
    StandInMeasure& operator=(const StandInMeasure&) = delete;

    [[nodiscard]] MeasuredStandIn measure(const StandIn& candidate);
    /** Whether the cell should keep `a` rather than `b` (both measured, both paying): the one
     *  whose views differ less from the source's where both are drawn (at the larger of their
     *  errors, by mean difference), else prefer(). */
    [[nodiscard]] bool firstIsBetter(
            const StandIn& a, const MeasuredStandIn& aMeasured, const StandIn& b, const MeasuredStandIn& bMeasured);

private:
    /** The source's views with the cell `span` pixels across (drawn on first use). */
    const CellViews& sourceViews(int span);
    [[nodiscard]] CellViews blankViews(int span) const;
    /** A box with a finite, positive largest side (else nothing is measured, nothing pays). */
    [[nodiscard]] bool measurable() const noexcept { return mSide > 0.0f && std::isfinite(mSide); }
    /** `candidate` (drawn as at `candidateError`) against the source, viewed where a pixel is
     *  `viewError` (the shift allowed). */
    [[nodiscard]] ViewDifference compareAt(const StandIn& candidate, float candidateError, float viewError);

    std::span<const storage::PackedTriangle> mSource;
    glm::vec3 mMin;
    glm::vec3 mMax;
    float mSide = 0.0f;
    std::map<int, CellViews> mSourceViews;
};

/** Of two measured candidates that look alike, which a cell keeps: true for `a` (see above). */
[[nodiscard]] bool prefer(const MeasuredStandIn& a, std::size_t aElements, const MeasuredStandIn& b, std::size_t bElements);

/** A stand-in's elements: its triangles and splats (a point costs about what a triangle does). */
[[nodiscard]] std::size_t elementsOf(const StandIn& standIn) noexcept;

} // namespace ff::builder
