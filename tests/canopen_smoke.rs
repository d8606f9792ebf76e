use ecdrive::canopen::emu::{EmulatedNode, SimBus};
use ecdrive::canopen::master::{DriveSetup, Master, MasterConfig};
use ecdrive::cia402::{OperationMode, ProfilePosition, SetPoint};
use ecdrive::drives::blv_r;

#[test]
fn smoke() {
    let mut bus = SimBus::new();
    bus.add_node(EmulatedNode::new(&blv_r::PROFILE, 3).unwrap());
    let mut m = Master::new(bus, MasterConfig::default());
    m.pump(10_000).unwrap();
    while let Some(e) = m.poll_event() {
        println!("{e}");
    }
    let mut setup = DriveSetup::new(&blv_r::PROFILE);
    setup.settings.push((
        ecdrive::od::ObjectAddress::new(0x6081, 0),
        ecdrive::od::Value::Uint(600),
    ));
    m.configure_drive(3, setup).unwrap();
    m.start(3).unwrap();
    m.enable(3, 1_000_000).unwrap();
    println!("enabled at {} us", m.now_us());
    let mut pp = ProfilePosition::default();
    pp.push(SetPoint::absolute(36_000)).unwrap();
    let mut done = false;
    for i in 0..2000 {
        let mut st = None;
        m.cycle_step(|d| {
            let sw = d.statusword();
            st = Some(pp.step(d.axis_mut(), sw));
        })
        .unwrap();
        let st = st.unwrap();
        if i % 50 == 0 {
            println!(
                "{i} {:?} pos {:?}",
                st,
                m.drive(3).unwrap().feedback().position
            );
        }
        if st.target_reached && st.acknowledged == 1 {
            done = true;
            break;
        }
    }
    assert!(done);
    println!("pos {:?}", m.drive(3).unwrap().feedback().position);
    assert_eq!(m.transport().node(3).unwrap().position(), 36_000);
    let _ = OperationMode::ProfilePosition;
}
