use crosscheck::case;
#[test]
fn every_case_file_validates() {
    let files = case::discover(&case::cases_dir()).unwrap();
    assert_eq!(files.len(), 13, "13 cases expected");
    for f in files {
        let scene = case::load(&f).unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.duration() > 0.0);
    }
}
