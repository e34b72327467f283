//! Sweep files through what `lightgraph validate` and `bench --sweep` run before the GPU:
//! parse and the limit checks (`Sweep::parse`), then the point count the progress bar
//! shows, the reference each graph compares against and the timing settings.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lightgraph::bench::sweep::Sweep;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let file = std::path::Path::new("/nonexistent-lightgraph-fuzz/sweep.ron");
    if let Ok(sweep) = Sweep::parse(&text, file) {
        let _ = sweep.point_count();
        for g in &sweep.graphs {
            let _ = sweep.reference_for(g);
        }
    }
});
