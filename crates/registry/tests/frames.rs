use raybench_registry::frames::*;
use std::path::Path;

#[test]
fn frame_names() {
    let p = Path::new("out/moving.png");
    assert_eq!(numbered(p, 0, 1), p);
    assert_eq!(numbered(p, 3, 16), Path::new("out/moving-0003.png"));
    assert_eq!(numbered(p, 7, 20_000), Path::new("out/moving-00007.png"));
    assert_eq!(numbered(Path::new("a"), 2, 3), Path::new("a-0002"));
}
