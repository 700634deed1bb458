//! The tree does not depend on the number of threads that built it (obvhs builds in parallel on
//! the current rayon pool): a render resumed on a machine with another core count must trace
//! the same tree, or the films would differ wherever a ray ties between two triangles.

use furnace_accel::{BuildOptions, BuildQuality, Bvh};

fn build_on(threads: usize, positions: &[glam::Vec3], triangles: &[[u32; 3]], quality: BuildQuality) -> Bvh {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool");
    pool.install(|| {
        Bvh::from_indexed(positions, triangles, BuildOptions { quality: Some(quality), ..Default::default() })
    })
}

#[test]
fn trees_are_the_same_on_one_two_and_three_threads() {
    // The sunlit interior (~30 k triangles: walls, floor and furniture of very different sizes,
    // so reinsertion and the pre-splits have work to do) under the presets the renderers choose
    // by size up to 3 M triangles.
    let scene = furnace_scene::builtin::sunlit_interior(30_000);
    let g = &scene.geometry;
    for quality in [BuildQuality::VerySlow, BuildQuality::Medium] {
        let one = build_on(1, &g.positions, &g.triangles, quality);
        for threads in [2, 3] {
            let other = build_on(threads, &g.positions, &g.triangles, quality);
            assert!(
                one.gpu_nodes() == other.gpu_nodes() && one.triangle_ids() == other.triangle_ids(),
                "{quality:?}: the tree built on {threads} threads differs from the one-thread tree \
                 ({} against {} nodes)",
                other.gpu_nodes().len(),
                one.gpu_nodes().len()
            );
        }
    }
}
