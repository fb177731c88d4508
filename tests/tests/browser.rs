//! The browser check of the fixture (`dmp_tests::browser`) itself: it must see a page's console messages and tell
//! a blank page from a drawn one, or the checks of `report.html` in `sims.rs` could not fail.

use dmp_tests::browser::open;

#[test]
fn the_browser_check_sees_console_errors_and_blank_pages() {
    let dir = tempfile::tempdir().unwrap();
    let broken = dir.path().join("broken.html");
    std::fs::write(
        &broken,
        "<!DOCTYPE html><html><body><h1>Drawn</h1><script>console.error('boom'); missing();</script></body></html>",
    )
    .unwrap();
    let shot = open(&broken, (400, 300));
    assert_eq!(shot.console.len(), 2, "{:#?}", shot.console);
    assert!(shot.console.iter().any(|l| l.contains("boom")));
    assert!(shot.ink > 0.0, "the heading is drawn");

    let blank = dir.path().join("blank.html");
    std::fs::write(&blank, "<!DOCTYPE html><html><body></body></html>").unwrap();
    let shot = open(&blank, (400, 300));
    assert!(shot.console.is_empty(), "{:#?}", shot.console);
    assert_eq!(shot.size, (400, 300));
    assert!(shot.luminance_variance < 1.0 && shot.ink == 0.0, "a blank page: {shot:?}");
}
