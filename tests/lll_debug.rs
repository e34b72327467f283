mod common;
use common::*;
#[test]
fn dbg() {
    let mut r = renderer();
    let s = random_scene(50, 7);
    let text = std::fs::read_to_string(graph_path("light_linked_list.ron")).unwrap();
    let out = render_text(&mut r, &text, &s, 64, 48);
    let bf = render_file(&mut r, "brute_force.ron", &s, 64, 48);
    println!("{:?}", max_rel_diff(&out.image, &bf.image));
    let text = std::fs::read_to_string(graph_path("forward_plus.ron")).unwrap();
    let fp = render_text(&mut r, &text, &s, 64, 48);
    println!("{:?} {:?}", fp.pass_ms, out.pass_ms);
    println!("{:?}", max_rel_diff(&fp.image, &bf.image));
}
