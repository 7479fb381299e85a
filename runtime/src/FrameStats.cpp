#include <ff/runtime/FrameStats.h>

#include <nlohmann/json.hpp>

namespace ff::runtime {

std::string FrameStats::toJson() const {
    const nlohmann::json j = {
            {"nodes_visited", nodesVisited},
            {"nodes_culled", nodesCulled},
            {"nodes_occluded", nodesOccluded},
            {"triangles_occluded", trianglesOccluded},
            {"instances_entered", instancesEntered},
            {"cubes_drawn", cubesDrawn},
            {"cube_faces_drawn", cubeFacesDrawn},
            {"occluder_cubes", occluderCubes},
            {"cube_faces_per_level", cubeFacesPerLevel},
            {"triangles_drawn", trianglesDrawn},
            {"stand_ins_drawn", standInsDrawn},
            {"splat_sets_drawn", splatSetsDrawn},
            {"splats_drawn", splatsDrawn},
            {"representation_fallbacks", representationFallbacks},
            {"geometry_draws", geometryDraws},
            {"pages_uploaded", pagesUploaded},
            {"nodes_deferred", nodesDeferred},
            {"pages_missing", pagesMissing},
            {"uploads_refused", uploadsRefused},
            {"pages_decoded_on_draw", pagesDecodedOnDraw},
            {"occlusion_queries", occlusionQueries},
            {"queries_waited", queriesWaited},
            {"occlusion_skipped", occlusionSkipped},
            {"select_ms", selectMs},
            {"occlusion_ms", occlusionMs},
            {"draw_ms", drawMs},
            {"total_ms", totalMs},
    };
    return j.dump();
}

} // namespace ff::runtime
