// D-BVD, p-HBVO, balanced and ORSD (Meißner, Bartz et al. 1999, §3); docs/methods.md §10.

#include "Decomposition.h"

#include "Morton.h"

#include <ff/storage/Assert.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>

namespace ff::builder {

namespace {

constexpr int kSahBins = 32;
constexpr std::uint32_t kMaxSlabs = 32;
constexpr int kPlaneBinsPerSlab = 64; ///< resolution at which D-BVD looks for a plane cutting less

struct Box {
    glm::vec3 lo{std::numeric_limits<float>::infinity()};
    glm::vec3 hi{-std::numeric_limits<float>::infinity()};
    void grow(const glm::vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void grow(const Box& b) {
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
    bool empty() const { return !(lo.x <= hi.x); }
    float area() const {
        if (empty())
            return 0.0f;
        const glm::vec3 d = hi - lo;
        return 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
    }
};

/** A box the cube baker can project onto: flat sides get a sliver of thickness. */
void padFlat(glm::vec3& lo, glm::vec3& hi) {
    const glm::vec3 size = hi - lo;
    const float least =
            std::max({size.x, size.y, size.z}) * 1e-4f + std::numeric_limits<float>::min();
    for (int a = 0; a < 3; ++a)
        if (size[a] < least) {
            lo[a] -= 0.5f * least;
            hi[a] += 0.5f * least;
        }
}

/** Children of one split: consecutive ranges of `order`; `leaf` ones are not split again. */
struct Split {
    struct Child {
        std::uint64_t begin = 0;
        std::uint64_t end = 0;
        bool leaf = false;
        int octant = 0;
        GridBlock block{};
    };
    std::vector<Child> children;
    bool octreeChildren = false;
};

class Decomposer {
public:
    Decomposer(
            std::span<const SplitItem> items,
            std::vector<std::uint32_t>& order,
            Decomposition decomposition,
            const DecompositionParams& params,
            const VoxelGrid* grid)
        : mItems(items)
        , mOrder(order)
        , mDecomposition(decomposition)
        , mParams(params)
        , mGrid(grid) {}

    std::vector<SplitNode> run(GridBlock block) {
        mOrder.resize(mItems.size());
        std::iota(mOrder.begin(), mOrder.end(), 0u);
        if (mDecomposition == Decomposition::Orsd)
            prepareCells(block);
        mNodes.emplace_back();
        build(0, 0, mItems.size(), 0, false, block);
        return std::move(mNodes);
    }

private:
    Box boundsOf(std::uint64_t begin, std::uint64_t end) const {
        Box box;
        for (std::uint64_t i = begin; i < end; ++i) {
            box.grow(mItems[mOrder[i]].lo);
            box.grow(mItems[mOrder[i]].hi);
        }
        return box;
    }

    void
    build(std::size_t index,
          std::uint64_t begin,
          std::uint64_t end,
          int level,
          bool leaf,
          GridBlock block) {
        const Box bounds = boundsOf(begin, end);
        Split split;
        if (!leaf && level < mParams.maxDepth && end - begin > 1)
            split = splitRange(begin, end, bounds, block);
        SplitNode& node = mNodes[index];
        node.begin = begin;
        node.end = end;
        node.ownEnd = split.children.empty() ? end : begin;
        node.boundsMin = bounds.lo;
        node.boundsMax = bounds.hi;
        node.cellMin = bounds.lo;
        node.cellMax = bounds.hi;
        padFlat(node.cellMin, node.cellMax);
        if (mDecomposition == Decomposition::Orsd && mGrid) {
            node.cellMin = mGrid->origin + glm::vec3(block.first) * mGrid->cellSize;
            node.cellMax =
                    node.cellMin + glm::vec3(static_cast<float>(block.size) * mGrid->cellSize);
        }
        node.level = level;
        node.octreeChildren = split.octreeChildren;
        if (split.children.empty())
            return;
        const auto firstChild = static_cast<std::uint32_t>(mNodes.size());
        node.firstChild = firstChild;
        node.childCount = static_cast<std::uint32_t>(split.children.size());
        mNodes.resize(mNodes.size() + split.children.size()); // `node` is invalid from here
        for (std::size_t c = 0; c < split.children.size(); ++c) {
            const Split::Child& child = split.children[c];
            mNodes[firstChild + c].octant = child.octant;
            build(firstChild + c, child.begin, child.end, level + 1, child.leaf, child.block);
        }
    }

    Split splitRange(std::uint64_t begin, std::uint64_t end, const Box& bounds, GridBlock block) {
        const std::uint64_t count = end - begin;
        switch (mDecomposition) {
        case Decomposition::Dbvd:
            if (count <= mParams.minTriangles)
                return {};
            return splitDimension(begin, end, bounds);
        case Decomposition::Phbvo:
            if (count <= mParams.maxTriangles)
                return {};
            return splitSurfaceArea(begin, end);
        case Decomposition::Balanced:
            if (count <= mParams.maxTriangles)
                return {};
            return splitBalanced(begin, end, bounds);
        case Decomposition::Orsd:
            return splitBlock(begin, end, block);
        case Decomposition::Octree:
            break;
        }
        FF_ASSERT(false); // the octree is not built here
        return {};
    }

    // ---- shared ------------------------------------------------------------------------------

    static int longestAxis(const glm::vec3& size) {
        return size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
    }

    /** Cuts [begin, end) at the median barycentre along `axis` (ties by item index): the split
     *  of last resort, when no plane separates the items (identical ones, say). */
    std::uint64_t medianCut(std::uint64_t begin, std::uint64_t end, int axis) {
        const std::uint64_t middle = begin + (end - begin) / 2;
        std::nth_element(
                mOrder.begin() + static_cast<std::ptrdiff_t>(begin),
                mOrder.begin() + static_cast<std::ptrdiff_t>(middle),
                mOrder.begin() + static_cast<std::ptrdiff_t>(end),
                [&](std::uint32_t a, std::uint32_t b) {
                    const float ca = mItems[a].centre[axis];
                    const float cb = mItems[b].centre[axis];
                    return ca < cb || (ca == cb && a < b);
                });
        return middle;
    }

    Split medianSplit(std::uint64_t begin, std::uint64_t end, const Box& bounds) {
        const std::uint64_t middle = medianCut(begin, end, longestAxis(bounds.hi - bounds.lo));
        Split split;
        split.children = {{begin, middle, false, 0, {}}, {middle, end, false, 0, {}}};
        return split;
    }

    // ---- p-HBVO: binned SAH ------------------------------------------------------------------

    /** Where the cheapest plane of C = S(l)/S(h)·|l| + S(r)/S(h)·|r| cuts [begin, end), over
     *  kSahBins bins of barycentres per axis (the paper evaluates every barycentre; binning
     *  keeps a level linear). Falls back to the median when no plane separates the items. */
    std::uint64_t surfaceAreaCut(std::uint64_t begin, std::uint64_t end) {
        Box centres;
        for (std::uint64_t i = begin; i < end; ++i)
            centres.grow(mItems[mOrder[i]].centre);
        float bestCost = std::numeric_limits<float>::infinity();
        int bestAxis = -1;
        int bestBin = 0;
        for (int axis = 0; axis < 3; ++axis) {
            const float lo = centres.lo[axis];
            const float extent = centres.hi[axis] - lo;
            if (!(extent > 0.0f))
                continue;
            std::array<Box, kSahBins> boxes;
            std::array<std::uint64_t, kSahBins> counts{};
            for (std::uint64_t i = begin; i < end; ++i) {
                const SplitItem& item = mItems[mOrder[i]];
                const int bin = binOf(item.centre[axis], lo, extent);
                boxes[static_cast<std::size_t>(bin)].grow(item.lo);
                boxes[static_cast<std::size_t>(bin)].grow(item.hi);
                ++counts[static_cast<std::size_t>(bin)];
            }
            std::array<float, kSahBins> rightCost{};
            Box right;
            std::uint64_t rightCount = 0;
            for (int b = kSahBins - 1; b > 0; --b) {
                right.grow(boxes[static_cast<std::size_t>(b)]);
                rightCount += counts[static_cast<std::size_t>(b)];
                rightCost[static_cast<std::size_t>(b)] =
                        right.area() * static_cast<float>(rightCount);
            }
            Box left;
            std::uint64_t leftCount = 0;
            for (int b = 1; b < kSahBins; ++b) {
                left.grow(boxes[static_cast<std::size_t>(b - 1)]);
                leftCount += counts[static_cast<std::size_t>(b - 1)];
                if (leftCount == 0 || leftCount == end - begin)
                    continue;
                const float cost = left.area() * static_cast<float>(leftCount) +
                                   rightCost[static_cast<std::size_t>(b)];
                if (cost < bestCost) {
                    bestCost = cost;
                    bestAxis = axis;
                    bestBin = b;
                }
            }
        }
        if (bestAxis < 0) { // every barycentre in one place
            return medianCut(begin, end, 0);
        }
        const float lo = centres.lo[bestAxis];
        const float extent = centres.hi[bestAxis] - lo;
        const auto first = mOrder.begin() + static_cast<std::ptrdiff_t>(begin);
        const auto last = mOrder.begin() + static_cast<std::ptrdiff_t>(end);
        const auto cut = std::stable_partition(first, last, [&](std::uint32_t i) {
            return binOf(mItems[i].centre[bestAxis], lo, extent) < bestBin;
        });
        return static_cast<std::uint64_t>(cut - mOrder.begin());
    }

    static int binOf(float value, float lo, float extent) {
        const auto bin = static_cast<int>((value - lo) / extent * static_cast<float>(kSahBins));
        return std::clamp(bin, 0, kSahBins - 1);
    }

    Split splitSurfaceArea(std::uint64_t begin, std::uint64_t end) {
        const std::uint64_t cut = surfaceAreaCut(begin, end);
        std::vector<std::pair<std::uint64_t, std::uint64_t>> halves = {{begin, cut}, {cut, end}};
        Split split;
        for (const auto& [b, e] : halves) {
            // The collapsed quad tree: a half that would split again splits now.
            if (mParams.arity >= 4 && e - b > mParams.maxTriangles) {
                const std::uint64_t quarter = surfaceAreaCut(b, e);
                split.children.push_back({b, quarter, false, 0, {}});
                split.children.push_back({quarter, e, false, 0, {}});
            } else {
                split.children.push_back({b, e, false, 0, {}});
            }
        }
        return split;
    }

    // ---- D-BVD -------------------------------------------------------------------------------

    Split splitDimension(std::uint64_t begin, std::uint64_t end, const Box& bounds) {
        const glm::vec3 size = bounds.hi - bounds.lo;
        const int axis = longestAxis(size);
        if (size[axis] <= mParams.minSize || !(size[axis] > 0.0f))
            return size[axis] > mParams.minSize ? medianSplit(begin, end, bounds) : Split{};
        std::array<float, 3> sorted = {size.x, size.y, size.z};
        std::sort(sorted.begin(), sorted.end());
        const float second = std::max(sorted[1], size[axis] / static_cast<float>(kMaxSlabs));
        // Equation (1): n slabs about as long as the second-largest side.
        const auto slabs = std::clamp<std::uint32_t>(
                static_cast<std::uint32_t>(std::lround(size[axis] / second)), 2u, kMaxSlabs);
        const float slab = size[axis] / static_cast<float>(slabs);

        // Triangles longer than a slab would be cut whatever the plane: pulled up into a
        // geometry node of their own at this level (the paper's factory floor).
        const auto first = mOrder.begin() + static_cast<std::ptrdiff_t>(begin);
        const auto last = mOrder.begin() + static_cast<std::ptrdiff_t>(end);
        const auto restBegin = std::stable_partition(first, last, [&](std::uint32_t i) {
            return mItems[i].hi[axis] - mItems[i].lo[axis] > slab;
        });
        const auto pulledEnd = static_cast<std::uint64_t>(restBegin - mOrder.begin());

        const std::vector<float> planes =
                choosePlanes(pulledEnd, end, bounds.lo[axis], slab, slabs, axis);
        auto slabOf = [&](std::uint32_t i) {
            return static_cast<std::uint32_t>(
                    std::upper_bound(planes.begin(), planes.end(), mItems[i].centre[axis]) -
                    planes.begin());
        };
        std::stable_sort(restBegin, last, [&](std::uint32_t a, std::uint32_t b) {
            return slabOf(a) < slabOf(b);
        });

        Split split;
        if (pulledEnd > begin)
            split.children.push_back({begin, pulledEnd, true, 0, {}});
        std::uint64_t cursor = pulledEnd;
        while (cursor < end) {
            const std::uint32_t s = slabOf(mOrder[cursor]);
            std::uint64_t next = cursor;
            while (next < end && slabOf(mOrder[next]) == s)
                ++next;
            split.children.push_back({cursor, next, false, 0, {}});
            cursor = next;
        }
        if (split.children.size() == 1 && !split.children[0].leaf) // no plane separated them
            return medianSplit(begin, end, bounds);
        if (pulledEnd == end) // nothing but long items: pulling them up would not progress
            return medianSplit(begin, end, bounds);
        return split;
    }

    /** The slab boundaries, each moved within ±planeShift of a slab to where it crosses the
     *  fewest of the items [begin, end) (nearest to the even plane on ties). */
    std::vector<float> choosePlanes(
            std::uint64_t begin,
            std::uint64_t end,
            float lo,
            float slab,
            std::uint32_t slabs,
            int axis) const {
        const std::uint32_t bins = slabs * kPlaneBinsPerSlab;
        const float binWidth = slab / static_cast<float>(kPlaneBinsPerSlab);
        auto binOfValue = [&](float v) {
            return std::clamp<std::int64_t>(
                    static_cast<std::int64_t>(std::floor((v - lo) / binWidth)), 0, bins - 1);
        };
        // At the edge between bins j-1 and j: items starting below it minus items ending below it.
        std::vector<std::int64_t> starts(bins + 1, 0);
        std::vector<std::int64_t> ends(bins + 1, 0);
        for (std::uint64_t i = begin; i < end; ++i) {
            const SplitItem& item = mItems[mOrder[i]];
            ++starts[static_cast<std::size_t>(binOfValue(item.lo[axis]) + 1)];
            ++ends[static_cast<std::size_t>(binOfValue(item.hi[axis]) + 1)];
        }
        for (std::uint32_t j = 1; j <= bins; ++j) {
            starts[j] += starts[j - 1];
            ends[j] += ends[j - 1];
        }
        const float shift = std::clamp(mParams.planeShift, 0.0f, 0.45f);
        const auto window =
                static_cast<std::int64_t>(shift * static_cast<float>(kPlaneBinsPerSlab));
        std::vector<float> planes;
        for (std::uint32_t k = 1; k < slabs; ++k) {
            const std::int64_t even = static_cast<std::int64_t>(k) * kPlaneBinsPerSlab;
            std::int64_t best = even;
            std::int64_t bestCut =
                    starts[static_cast<std::size_t>(even)] - ends[static_cast<std::size_t>(even)];
            for (std::int64_t d = 1; d <= window; ++d)
                for (const std::int64_t j : {even - d, even + d}) {
                    const std::int64_t cut =
                            starts[static_cast<std::size_t>(j)] - ends[static_cast<std::size_t>(j)];
                    if (cut < bestCut) {
                        bestCut = cut;
                        best = j;
                    }
                }
            planes.push_back(lo + static_cast<float>(best) * binWidth);
        }
        return planes;
    }

    // ---- balanced ----------------------------------------------------------------------------

    /** Up to eight children at the median planes of the longest axes, as many ways as keep
     *  every child at tri_min or more. */
    Split splitBalanced(std::uint64_t begin, std::uint64_t end, const Box& bounds) {
        const std::uint64_t count = end - begin;
        const std::uint64_t least = std::max<std::uint64_t>(mParams.balancedMinTriangles, 1);
        const int ways = count / 8 >= least ? 3 : (count / 4 >= least ? 2 : 1);
        const glm::vec3 size = bounds.hi - bounds.lo;
        std::array<int, 3> axes = {0, 1, 2};
        std::stable_sort(axes.begin(), axes.end(), [&](int a, int b) { return size[a] > size[b]; });
        std::vector<std::pair<std::uint64_t, std::uint64_t>> pieces = {{begin, end}};
        for (int w = 0; w < ways; ++w) {
            std::vector<std::pair<std::uint64_t, std::uint64_t>> next;
            for (const auto& [b, e] : pieces) {
                if (e - b < 2) {
                    next.emplace_back(b, e);
                    continue;
                }
                const std::uint64_t middle = medianCut(b, e, axes[static_cast<std::size_t>(w)]);
                next.emplace_back(b, middle);
                next.emplace_back(middle, e);
            }
            pieces = std::move(next);
        }
        Split split;
        for (const auto& [b, e] : pieces)
            if (e > b)
                split.children.push_back({b, e, false, 0, {}});
        return split;
    }

    // ---- ORSD --------------------------------------------------------------------------------

    /** Each item's grid cell (from its barycentre, kept inside the starting block) as a Morton
     *  key; the items sorted by it, so every block is one run of keys. */
    void prepareCells(GridBlock block) {
        FF_ASSERT(mGrid != nullptr); // ORSD needs a voxel grid
        mCellKeys.resize(mItems.size());
        const glm::uvec3 last = block.first + glm::uvec3(block.size - 1);
        for (std::size_t i = 0; i < mItems.size(); ++i) {
            const glm::vec3 t = (mItems[i].centre - mGrid->origin) / mGrid->cellSize;
            glm::uvec3 cell;
            for (int a = 0; a < 3; ++a) {
                const float c = std::floor(t[a]);
                cell[a] = static_cast<std::uint32_t>(std::clamp(
                        c, static_cast<float>(block.first[a]), static_cast<float>(last[a])));
            }
            mCellKeys[i] = mortonKey(cell);
        }
        std::sort(mOrder.begin(), mOrder.end(), [&](std::uint32_t a, std::uint32_t b) {
            return mCellKeys[a] < mCellKeys[b] || (mCellKeys[a] == mCellKeys[b] && a < b);
        });
    }

    /** The relevant-cell load: distinct cells among the (key-sorted) items. */
    std::uint64_t relevantCells(std::uint64_t begin, std::uint64_t end) const {
        std::uint64_t cells = 0;
        for (std::uint64_t i = begin; i < end; ++i)
            cells += (i == begin || mCellKeys[mOrder[i]] != mCellKeys[mOrder[i - 1]]) ? 1u : 0u;
        return cells;
    }

    Split splitBlock(std::uint64_t begin, std::uint64_t end, GridBlock block) {
        if (block.size < 2 || relevantCells(begin, end) <= mParams.relevantCells)
            return {};
        const std::uint32_t half = block.size / 2;
        const std::uint64_t childKeys = static_cast<std::uint64_t>(half) * half * half;
        const std::uint64_t base = mortonKey(block.first);
        Split split;
        split.octreeChildren = true;
        std::uint64_t cursor = begin;
        for (int octant = 0; octant < 8; ++octant) {
            const std::uint64_t limit = base + childKeys * static_cast<std::uint64_t>(octant + 1);
            const auto stop = std::partition_point(
                    mOrder.begin() + static_cast<std::ptrdiff_t>(cursor),
                    mOrder.begin() + static_cast<std::ptrdiff_t>(end),
                    [&](std::uint32_t i) { return mCellKeys[i] < limit; });
            const auto next = static_cast<std::uint64_t>(stop - mOrder.begin());
            if (next > cursor) {
                GridBlock child;
                child.first = block.first +
                              glm::uvec3(octant & 1, (octant >> 1) & 1, (octant >> 2) & 1) * half;
                child.size = half;
                split.children.push_back({cursor, next, false, octant, child});
            }
            cursor = next;
        }
        return split;
    }

    std::span<const SplitItem> mItems;
    std::vector<std::uint32_t>& mOrder;
    Decomposition mDecomposition;
    const DecompositionParams& mParams;
    const VoxelGrid* mGrid;
    std::vector<std::uint64_t> mCellKeys; ///< ORSD: per item
    std::vector<SplitNode> mNodes;
};

} // namespace

std::string_view decompositionName(Decomposition decomposition) noexcept {
    switch (decomposition) {
    case Decomposition::Octree:
        return "octree";
    case Decomposition::Dbvd:
        return "dbvd";
    case Decomposition::Phbvo:
        return "phbvo";
    case Decomposition::Balanced:
        return "balanced";
    case Decomposition::Orsd:
        return "orsd";
    }
    return "octree";
}

std::optional<Decomposition> parseDecomposition(std::string_view name) noexcept {
    for (const Decomposition d :
         {Decomposition::Octree,
          Decomposition::Dbvd,
          Decomposition::Phbvo,
          Decomposition::Balanced,
          Decomposition::Orsd})
        if (decompositionName(d) == name)
            return d;
    return std::nullopt;
}

std::optional<GridBlock> gridBlockOf(const VoxelGrid& grid, const glm::vec3& min, float edge) {
    const float cells = edge / grid.cellSize;
    const auto size = static_cast<std::uint32_t>(std::lround(cells));
    if (size == 0 || !std::has_single_bit(size) ||
        std::abs(cells - static_cast<float>(size)) > 1e-3f * cells)
        return std::nullopt;
    GridBlock block;
    block.size = size;
    for (int a = 0; a < 3; ++a) {
        const float first = (min[a] - grid.origin[a]) / grid.cellSize;
        const long rounded = std::lround(first);
        if (rounded < 0 ||
            std::abs(first - static_cast<float>(rounded)) >
                    1e-3f * std::max(1.0f, std::abs(first)) ||
            rounded % static_cast<long>(size) != 0)
            return std::nullopt;
        block.first[a] = static_cast<std::uint32_t>(rounded);
    }
    return block;
}

GridBlock rootGridBlock(const VoxelGrid& grid) {
    const std::uint32_t largest = std::max({grid.cells.x, grid.cells.y, grid.cells.z, 1u});
    return {glm::uvec3(0u), std::bit_ceil(largest)};
}

std::vector<SplitNode> decompose(
        std::span<const SplitItem> items,
        std::vector<std::uint32_t>& order,
        Decomposition decomposition,
        const DecompositionParams& params,
        const VoxelGrid* grid,
        GridBlock block) {
    FF_ASSERT(decomposition != Decomposition::Octree); // the octree is built by buildOctree
    FF_ASSERT(!items.empty());                         // nothing to decompose
    FF_ASSERT(items.size() < 0xFFFFFFFFull);           // item indices are 32-bit
    return Decomposer(items, order, decomposition, params, grid).run(block);
}

} // namespace ff::builder
