use ecdrive::canopen::demo;

#[test]
fn demo_runs_every_drive_through_every_mode() {
    let s = demo::run(&demo::DemoOptions::default()).unwrap();
    println!("{s}");
    assert!(s.ok(), "{s}");
}
