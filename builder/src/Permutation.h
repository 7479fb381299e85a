#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace ff::builder {

/** Moves items[i] to items[destination[i]] for every i, in place (cycle by cycle, one swap a
 *  move). `destination` must be a permutation of [0, items.size()); it is consumed (left the
 *  identity). 4 bytes an item: within the builder's per-triangle memory plan. */
template <class Item>
void permuteInPlace(std::span<Item> items, std::vector<std::uint32_t>& destination) {
    for (std::size_t i = 0; i < items.size(); ++i) {
        while (destination[i] != i) {
            const std::uint32_t j = destination[i];
            std::swap(items[i], items[j]);
            std::swap(destination[i], destination[j]);
        }
    }
}

} // namespace ff::builder
