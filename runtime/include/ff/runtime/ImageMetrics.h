#pragma once

// Image-error metrics for the speed-against-accuracy work: how far an approximate rendering
// (coarser LOD, smaller budget, cheaper shading) is from a reference rendering of the same view.
// Definitions, units and how to read the numbers: docs/metrics.md.
//
// All functions are pure, O(pixels), use no OpenGL and create no threads; they are safe to call
// concurrently from any thread. Images may come from files, so every mismatch or malformed image
// is reported as a Status (InvalidArgument), never asserted.

#include <ff/runtime/Image.h>
#include <ff/storage/Status.h>

#include <cstddef>
#include <cstdint>
#include <span>

namespace ff::runtime {

/**
 * Colour error of the RGB channels (alpha is ignored: the colour is already composited over the
 * background, so a missing surface shows up as a colour error where it differs from the
 * background). Averages run over every pixel and all three channels.
 */
struct ColorError {
    double rmseSrgb = 0.0;   ///< RMSE of sRGB code values, 0..255
    double psnrSrgb = 0.0;   ///< 20 log10(255 / rmseSrgb) in dB; +infinity when identical
    double rmseLinear = 0.0; ///< RMSE after decoding sRGB to linear light, 0..1
    double psnrLinear = 0.0; ///< 20 log10(1 / rmseLinear) in dB; +infinity when identical
};

/**
 * RMSE and PSNR of `approximation` against `reference`, both in sRGB code values and in linear
 * light (decoded with the exact sRGB transfer function, float precision ~1e-7).
 * Fails with InvalidArgument when the sizes differ, an image is empty, or `rgba` does not hold
 * width * height * 4 bytes.
 */
[[nodiscard]] Result<ColorError> colorError(const Image& approximation, const Image& reference);

/** SSIM parameters of Wang, Bovik, Sheikh, Simoncelli 2004 ("Image quality assessment: from
 *  error visibility to structural similarity", IEEE TIP 13(4)); fixed so numbers compare. */
inline constexpr int kSsimWindowSize = 11;       ///< pixels per side of the Gaussian window
inline constexpr double kSsimSigma = 1.5;        ///< Gaussian standard deviation, pixels
inline constexpr double kSsimK1 = 0.01;          ///< C1 = (K1 L)^2
inline constexpr double kSsimK2 = 0.03;          ///< C2 = (K2 L)^2
inline constexpr double kSsimDynamicRange = 255; ///< L: luma is on the 0..255 code scale

/**
 * Mean SSIM of the luma Y' = 0.2126 R' + 0.7152 G' + 0.0722 B' (Rec. 709 coefficients applied to
 * the sRGB-coded values, 0..255, L = 255).
 *
 * Why coded luma and not linear luminance: SSIM's constants and its validation against human
 * ratings (LIVE database) were made on gamma-encoded 8-bit images, where equal code steps are
 * roughly equally visible in dark and bright areas. In linear light the structure of dark areas
 * would be compressed towards zero and barely count.
 *
 * Window: 11 x 11 Gaussian, sigma 1.5, weights normalised to sum 1. Borders: only "valid" window
 * positions count, i.e. windows lying entirely inside the image (as in the authors' reference
 * implementation, filter2(..., 'valid')); no padding. The result is the plain mean over the
 * (width - 10) * (height - 10) window positions, in [-1, 1]; exactly 1 for identical images.
 *
 * Allocates one scratch buffer of about 57 * width doubles per call.
 * Fails with InvalidArgument on a size mismatch, a malformed image, or an image smaller than the
 * window (width or height < 11).
 */
[[nodiscard]] Result<double> ssim(const Image& approximation, const Image& reference);

/** A pixel is "covered" when alpha / 255 >= threshold. */
inline constexpr float kDefaultCoverageThreshold = 0.5f;

/** Coverage disagreement between an approximation and its reference, from the alpha channels. */
struct CoverageError {
    /** Background shows in the approximation but the reference is covered: holes, "tearing". */
    std::uint64_t holes = 0;
    /** The approximation is covered but the reference shows background: "bleeding". */
    std::uint64_t overCoverage = 0;
    std::uint64_t pixelCount = 0;      ///< width * height
    double holeFraction = 0.0;         ///< holes / pixelCount, 0..1
    double overCoverageFraction = 0.0; ///< overCoverage / pixelCount, 0..1
};

/**
 * Counts pixels whose coverage (alpha / 255 >= `threshold`) differs between `approximation` and
 * `reference`. With the default 0.5, codes 0..127 are background and 128..255 covered.
 * Fails with InvalidArgument on a size mismatch, a malformed image, or a threshold outside
 * [0, 1] (NaN included).
 */
[[nodiscard]] Result<CoverageError> coverageError(
        const Image& approximation,
        const Image& reference,
        float threshold = kDefaultCoverageThreshold);

/**
 * Temporal instability of one consecutive frame pair: the mean over pixels of
 *     max(0, |A_t - A_{t-1}| - |R_t - R_{t-1}|)
 * where A is the approximation, R the reference of the same camera path, and each value is the
 * linear relative luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of the decoded linear RGB, 0..1.
 * Only change beyond the reference's own change counts: camera motion that the reference also
 * shows is free, flicker and popping of LOD switches are not. Linear light, unlike SSIM, because
 * this measures how much light changes on screen, which is what makes flicker visible.
 * Result in [0, 1]. Fails with InvalidArgument unless all four images have one size and are
 * well-formed.
 */
[[nodiscard]] Result<double> temporalInstability(
        const Image& previousApproximation,
        const Image& approximation,
        const Image& previousReference,
        const Image& reference);

/** Temporal instability over a whole sequence. Both values are in linear luminance, 0..1. */
struct TemporalInstability {
    /** Mean over pixels and frame pairs (all frames share one size, so this is also the mean of
     *  the per-pair values). */
    double mean = 0.0;
    double maxFrame = 0.0;      ///< largest per-pair value
    std::size_t framePairs = 0; ///< number of consecutive pairs seen (frames - 1)
};

/**
 * Accumulates per-pair values from temporalInstability(A_{t-1}, A_t, R_{t-1}, R_t) so a replay
 * loop keeps only the previous frames, not the sequence. Pairs must all have one image size for
 * `mean` to be the per-pixel mean. Not thread-safe; one accumulator per sequence.
 */
class TemporalInstabilityAccumulator {
public:
    /** Adds one pair's value (as returned by temporalInstability for a pair). */
    void add(double pairValue) noexcept;
    /** The sequence so far; all zero before the first add(). */
    TemporalInstability result() const noexcept;

private:
    double mSum = 0.0;
    double mMax = 0.0;
    std::size_t mCount = 0;
};

/**
 * Temporal instability of frames A_0..A_n against R_0..R_n (n >= 1), same camera path.
 * Fails with InvalidArgument when the frame counts differ, there are fewer than two frames, or
 * the frames do not all share one size.
 */
[[nodiscard]] Result<TemporalInstability>
temporalInstability(std::span<const Image> approximation, std::span<const Image> reference);

} // namespace ff::runtime
