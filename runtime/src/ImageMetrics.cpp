// Image-error metrics. SSIM follows Wang, Bovik, Sheikh, Simoncelli, "Image quality
// assessment: from error visibility to structural similarity", IEEE TIP 13(4), 2004, and the
// authors' reference ssim_index.m (Gaussian 11x11, sigma 1.5, 'valid' filtering).

#include <ff/runtime/ImageMetrics.h>
#include <ff/storage/VertexCodec.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace ff::runtime {

namespace {

constexpr double kLumaR = 0.2126;
constexpr double kLumaG = 0.7152;
constexpr double kLumaB = 0.0722;

std::size_t pixelCount(const Image& image) noexcept {
    return static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
}

std::string sizeText(const Image& image) {
    return std::to_string(image.width) + "x" + std::to_string(image.height);
}

Status checkWellFormed(const Image& image, const char* name) {
    if (image.width <= 0 || image.height <= 0)
        return {ErrorCode::InvalidArgument, std::string(name) + ": empty image " + sizeText(image)};
    if (image.rgba.size() != pixelCount(image) * 4)
        return {ErrorCode::InvalidArgument,
                std::string(name) + ": " + sizeText(image) + " image holds " +
                        std::to_string(image.rgba.size()) + " bytes, expected " +
                        std::to_string(pixelCount(image) * 4)};
    return Status::ok();
}

Status checkPair(
        const Image& first,
        const Image& second,
        const char* firstName = "approximation",
        const char* secondName = "reference") {
    FF_RETURN_IF_ERROR(checkWellFormed(first, firstName));
    FF_RETURN_IF_ERROR(checkWellFormed(second, secondName));
    if (first.width != second.width || first.height != second.height)
        return {ErrorCode::InvalidArgument,
                std::string("size mismatch: ") + firstName + " " + sizeText(first) + ", " +
                        secondName + " " + sizeText(second)};
    return Status::ok();
}

double linear(std::uint8_t code) noexcept {
    return storage::srgb8ToLinear(code);
}

/** 20 log10(peak / rmse); +infinity for rmse 0 so identical images compare as "perfect". */
double psnr(double peak, double rmse) noexcept {
    if (rmse == 0.0)
        return std::numeric_limits<double>::infinity();
    return 20.0 * std::log10(peak / rmse);
}

double codedLuma(const std::uint8_t* px) noexcept {
    return kLumaR * px[0] + kLumaG * px[1] + kLumaB * px[2];
}

double linearLuminance(const std::uint8_t* px) noexcept {
    return kLumaR * linear(px[0]) + kLumaG * linear(px[1]) + kLumaB * linear(px[2]);
}

/** Normalised 1D Gaussian; the 2D window is its outer product, which then also sums to 1. */
std::array<double, kSsimWindowSize> ssimKernel() noexcept {
    std::array<double, kSsimWindowSize> kernel{};
    constexpr int kRadius = kSsimWindowSize / 2;
    double sum = 0.0;
    for (int i = 0; i < kSsimWindowSize; ++i) {
        const double d = i - kRadius;
        kernel[static_cast<std::size_t>(i)] = std::exp(-d * d / (2.0 * kSsimSigma * kSsimSigma));
        sum += kernel[static_cast<std::size_t>(i)];
    }
    for (double& w : kernel)
        w /= sum;
    return kernel;
}

// Windowed moments filtered per window position: x, y, x^2, y^2, xy.
constexpr std::size_t kMoments = 5;

} // namespace

Result<ColorError> colorError(const Image& approximation, const Image& reference) {
    FF_RETURN_IF_ERROR(checkPair(approximation, reference));
    // Integer sum for the codes: exact for any image below 2^64 / 255^2 / 3 pixels.
    std::uint64_t sumSquaredCodes = 0;
    double sumSquaredLinear = 0.0;
    const std::size_t pixels = pixelCount(reference);
    for (std::size_t p = 0; p < pixels; ++p) {
        for (std::size_t c = 0; c < 3; ++c) {
            const std::uint8_t a = approximation.rgba[p * 4 + c];
            const std::uint8_t r = reference.rgba[p * 4 + c];
            const int d = int{a} - int{r};
            sumSquaredCodes += static_cast<std::uint64_t>(d * d);
            const double dl = linear(a) - linear(r);
            sumSquaredLinear += dl * dl;
        }
    }
    const auto samples = static_cast<double>(pixels * 3);
    ColorError error;
    error.rmseSrgb = std::sqrt(static_cast<double>(sumSquaredCodes) / samples);
    error.psnrSrgb = psnr(255.0, error.rmseSrgb);
    error.rmseLinear = std::sqrt(sumSquaredLinear / samples);
    error.psnrLinear = psnr(1.0, error.rmseLinear);
    return error;
}

Result<double> ssim(const Image& approximation, const Image& reference) {
    FF_RETURN_IF_ERROR(checkPair(approximation, reference));
    if (reference.width < kSsimWindowSize || reference.height < kSsimWindowSize)
        return Status{
                ErrorCode::InvalidArgument,
                "ssim needs at least " + std::to_string(kSsimWindowSize) + "x" +
                        std::to_string(kSsimWindowSize) + " pixels, got " + sizeText(reference)};

    const auto kernel = ssimKernel();
    const auto width = static_cast<std::size_t>(reference.width);
    const auto height = static_cast<std::size_t>(reference.height);
    const std::size_t window = kSsimWindowSize;
    const std::size_t outWidth = width - window + 1;
    const std::size_t outHeight = height - window + 1;

    // Separable filtering with a ring of the last `window` horizontally filtered rows, so
    // scratch is O(width) and each pixel costs 2 * 11 multiply-adds per moment.
    // Layout: [luma x | luma y | ring: window rows x kMoments x outWidth].
    std::vector<double> scratch(2 * width + window * kMoments * outWidth);
    double* lumaX = scratch.data();
    double* lumaY = lumaX + width;
    double* ring = lumaY + width;
    auto ringRow = [&](std::size_t row, std::size_t moment) {
        return ring + ((row % window) * kMoments + moment) * outWidth;
    };

    const double c1 = (kSsimK1 * kSsimDynamicRange) * (kSsimK1 * kSsimDynamicRange);
    const double c2 = (kSsimK2 * kSsimDynamicRange) * (kSsimK2 * kSsimDynamicRange);
    double ssimSum = 0.0;

    for (std::size_t y = 0; y < height; ++y) {
        // --- horizontal pass of row y into the ring ---
        for (std::size_t x = 0; x < width; ++x) {
            lumaX[x] = codedLuma(&approximation.rgba[(y * width + x) * 4]);
            lumaY[x] = codedLuma(&reference.rgba[(y * width + x) * 4]);
        }
        double* hx = ringRow(y, 0);
        double* hy = ringRow(y, 1);
        double* hxx = ringRow(y, 2);
        double* hyy = ringRow(y, 3);
        double* hxy = ringRow(y, 4);
        for (std::size_t ox = 0; ox < outWidth; ++ox) {
            double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
            for (std::size_t k = 0; k < window; ++k) {
                const double w = kernel[k];
                const double a = lumaX[ox + k];
                const double b = lumaY[ox + k];
                sx += w * a;
                sy += w * b;
                sxx += w * (a * a);
                syy += w * (b * b);
                sxy += w * (a * b);
            }
            hx[ox] = sx;
            hy[ox] = sy;
            hxx[ox] = sxx;
            hyy[ox] = syy;
            hxy[ox] = sxy;
        }
        if (y + 1 < window)
            continue;

        // --- vertical pass: window rows y-10..y give output row y-10 ---
        const std::size_t top = y + 1 - window;
        for (std::size_t ox = 0; ox < outWidth; ++ox) {
            std::array<double, kMoments> m{};
            for (std::size_t k = 0; k < window; ++k)
                for (std::size_t moment = 0; moment < kMoments; ++moment)
                    m[moment] += kernel[k] * ringRow(top + k, moment)[ox];
            const double muX = m[0];
            const double muY = m[1];
            // Written so identical inputs give bit-identical numerator and denominator
            // (2 * (a * a) == a * a + a * a exactly), hence SSIM exactly 1.
            const double muXY = muX * muY;
            const double varX = m[2] - muX * muX;
            const double varY = m[3] - muY * muY;
            const double covXY = m[4] - muXY;
            ssimSum += ((2.0 * muXY + c1) * (2.0 * covXY + c2)) /
                       ((muX * muX + muY * muY + c1) * (varX + varY + c2));
        }
    }
    return ssimSum / static_cast<double>(outWidth * outHeight);
}

Result<CoverageError>
coverageError(const Image& approximation, const Image& reference, float threshold) {
    FF_RETURN_IF_ERROR(checkPair(approximation, reference));
    if (!(threshold >= 0.0f && threshold <= 1.0f))
        return Status{
                ErrorCode::InvalidArgument,
                "coverage threshold must be in [0, 1], got " + std::to_string(threshold)};
    // Compare codes against threshold * 255 rather than dividing each alpha: same test, and a
    // threshold of 0.5 puts the cut at 127.5 so no code sits on it.
    const double cut = static_cast<double>(threshold) * 255.0;
    CoverageError error;
    error.pixelCount = pixelCount(reference);
    for (std::size_t p = 0; p < error.pixelCount; ++p) {
        const bool approxCovered = approximation.rgba[p * 4 + 3] >= cut;
        const bool refCovered = reference.rgba[p * 4 + 3] >= cut;
        error.holes += (!approxCovered && refCovered) ? 1u : 0u;
        error.overCoverage += (approxCovered && !refCovered) ? 1u : 0u;
    }
    const auto pixels = static_cast<double>(error.pixelCount);
    error.holeFraction = static_cast<double>(error.holes) / pixels;
    error.overCoverageFraction = static_cast<double>(error.overCoverage) / pixels;
    return error;
}

Result<double> temporalInstability(
        const Image& previousApproximation,
        const Image& approximation,
        const Image& previousReference,
        const Image& reference) {
    FF_RETURN_IF_ERROR(checkPair(approximation, reference));
    FF_RETURN_IF_ERROR(checkPair(
            previousApproximation, approximation, "previous approximation", "approximation"));
    FF_RETURN_IF_ERROR(checkPair(previousReference, reference, "previous reference", "reference"));
    const std::size_t pixels = pixelCount(reference);
    double sum = 0.0;
    for (std::size_t p = 0; p < pixels; ++p) {
        const double approxChange = std::abs(
                linearLuminance(&approximation.rgba[p * 4]) -
                linearLuminance(&previousApproximation.rgba[p * 4]));
        const double refChange = std::abs(
                linearLuminance(&reference.rgba[p * 4]) -
                linearLuminance(&previousReference.rgba[p * 4]));
        sum += std::max(0.0, approxChange - refChange);
    }
    return sum / static_cast<double>(pixels);
}

void TemporalInstabilityAccumulator::add(double pairValue) noexcept {
    mSum += pairValue;
    mMax = std::max(mMax, pairValue);
    ++mCount;
}

TemporalInstability TemporalInstabilityAccumulator::result() const noexcept {
    TemporalInstability result;
    result.framePairs = mCount;
    result.maxFrame = mMax;
    result.mean = mCount == 0 ? 0.0 : mSum / static_cast<double>(mCount);
    return result;
}

Result<TemporalInstability>
temporalInstability(std::span<const Image> approximation, std::span<const Image> reference) {
    if (approximation.size() != reference.size())
        return Status{
                ErrorCode::InvalidArgument,
                "frame count mismatch: approximation " + std::to_string(approximation.size()) +
                        ", reference " + std::to_string(reference.size())};
    if (approximation.size() < 2)
        return Status{
                ErrorCode::InvalidArgument,
                "temporal instability needs at least two frames, got " +
                        std::to_string(approximation.size())};
    TemporalInstabilityAccumulator accumulator;
    for (std::size_t t = 1; t < approximation.size(); ++t) {
        // Each pair checks previous against current, so by induction all frames share one size
        // and the mean over pairs is the mean over pixels and frames.
        auto pair = temporalInstability(
                approximation[t - 1], approximation[t], reference[t - 1], reference[t]);
        if (!pair.isOk())
            return pair.status().withContext(
                    "frames " + std::to_string(t - 1) + ".." + std::to_string(t));
        accumulator.add(*pair);
    }
    return accumulator.result();
}

} // namespace ff::runtime
