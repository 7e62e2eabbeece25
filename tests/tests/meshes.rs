//! The real meshes of `../shared/scenes` load with the triangle counts of SOURCES.md.

use raybench_core::PrimitiveKind;
use raybench_tests::load_or_skip;

fn triangles(scene: &str) -> Option<usize> {
    let s = load_or_skip(scene)?;
    let counts = s.geometry.count_by_kind();
    Some(
        counts
            .iter()
            .find(|(k, _)| *k == PrimitiveKind::Triangle)
            .unwrap()
            .1,
    )
}

macro_rules! count_tests {
    ($($test:ident => $scene:literal, $count:literal;)*) => {
        $(
            #[test]
            fn $test() {
                if let Some(n) = triangles($scene) {
                    assert_eq!(n, $count, "{} triangles", $scene);
                }
            }
        )*
    };
}

count_tests! {
    cornell_box => "cornell-box", 36;
    suzanne => "suzanne", 968;
    bunny_lowres => "bunny-lowres", 3674;
    teapot => "teapot", 6320;
    dabrovic_sponza => "dabrovic-sponza", 66454;
    bunny => "bunny", 69451;
}

#[test]
fn cornell_box_light_is_emissive() {
    let Some(s) = load_or_skip("cornell-box") else {
        return;
    };
    let light = s
        .materials
        .iter()
        .find(|m| m.name == "light")
        .expect("light material");
    assert_eq!(light.emission, raybench_core::Vec3::new(17.0, 12.0, 4.0));
}
