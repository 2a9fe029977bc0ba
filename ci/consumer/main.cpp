// The consumer test's program (ci/consumer-test.sh): loads a scene file with incise's scene
// API, builds it, runs its static solve and checks the result. Built against the installed
// package twice: by CMake (find_package(incise), CMakeLists.txt) and by pkg-config.
//
//   incise_consumer SCENE.json      e.g. <prefix>/share/incise/scenes/cantilever.json
//
// Exit 0 when the solve converged, every displacement is finite and every probe with a
// reference deflects the same way as the reference and by less than it (the cantilever: linear
// tetrahedra are too stiff in bending, thesis §3.3); 1 otherwise or on an error.

#include <incise/scene/scene_builder.hpp>
#include <incise/scene/scene_parser.hpp>
#include <incise/scene/scene_runner.hpp>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: incise_consumer SCENE.json\n");
    return 2;
  }
  try {
    const incise::scene::SceneSpec spec = incise::scene::load_scene(argv[1]);
    incise::scene::BuiltScene scene = incise::scene::build_scene(spec);
    const incise::scene::SceneRunResult result = incise::scene::run_scene(scene);
    bool ok = result.report.ok() && result.u.allFinite() && !result.probes.empty();
    std::printf("%s: %ld nodes, %s after %ld iterations\n", spec.name.c_str(),
                static_cast<long>(scene.mesh.num_points()),
                incise::solver::to_string(result.report.status), result.report.iterations);
    for (const incise::scene::ProbeResult& p : result.probes) {
      std::printf("probe %s: (%.4e, %.4e, %.4e) m", p.name.c_str(), p.value.x(), p.value.y(),
                  p.value.z());
      if (p.reference) {
        const double along = p.value.dot(*p.reference) / p.reference->squaredNorm();
        std::printf(", %.4f of the reference (relative error %.4f)", along, p.relative_error);
        ok = ok && along > 0.0 && along < 1.0;
      }
      std::printf("\n");
    }
    std::printf("%s\n", ok ? "consumer: ok" : "consumer: FAILED");
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "incise_consumer: %s\n", e.what());
    return 1;
  }
}
