//! 0x603F decoding with real codes from the manuals.

use crate::support::cia402_drives as drives;

use ecdrive_core::cia402::{ErrorClass, ErrorCode, ErrorEntry, ErrorSource};

/// BDHDE §10.2 Table 10-4: every code classifies into the range of its first digit(s).
#[test]
fn bdhde_fault_codes_classify_by_range() {
    use ErrorClass::*;
    let table = [
        (0x2214, Current),
        (0x2250, Current),
        (0x2310, Current),
        (0x2311, Current),
        (0x2330, Current),
        (0x2380, Current),
        (0x2382, Current),
        (0x3110, Voltage),
        (0x3120, Voltage),
        (0x3183, Voltage),
        (0x3199, Voltage),
        (0x4080, Temperature),
        (0x4310, Temperature),
        (0x5530, DeviceHardware),
        (0x5581, DeviceHardware),
        (0x5585, DeviceHardware),
        (0x5586, DeviceHardware),
        (0x6100, DeviceSoftware),
        (0x6320, DeviceSoftware),
        (0x6381, DeviceSoftware),
        (0x6581, DeviceSoftware),
        (0x7090, AdditionalModules),
        (0x7091, AdditionalModules),
        (0x7121, AdditionalModules),
        (0x7305, AdditionalModules),
        (0x7380, AdditionalModules),
        (0x7382, AdditionalModules),
        (0x7385, AdditionalModules),
        (0x7388, AdditionalModules),
        (0x738D, AdditionalModules),
        (0x7580, AdditionalModules),
        (0x818D, Monitoring),
        (0x8481, Monitoring),
        (0x8482, Monitoring),
        (0x8689, Monitoring),
        (0xF080, AdditionalFunctions),
        (0xFF02, DeviceSpecific),
        (0xFF04, DeviceSpecific),
        (0xFF14, DeviceSpecific),
    ];
    for (code, class) in table {
        assert_eq!(ErrorCode(code).class(), class, "0x{code:04X}");
    }
}

/// BDHDE: the manual's own example (motor foldback → 0x2310) and vendor names from its table,
/// looked up before the standard names.
#[test]
fn bdhde_codes_with_the_drive_table() {
    let d = ErrorCode(0x2310).describe(drives::BDHDE_ERRORS);
    assert_eq!(d.source, ErrorSource::Drive);
    assert_eq!(d.text, "Motor Foldback");
    assert_eq!(d.class, ErrorClass::Current);
    assert_eq!(
        d.to_string(),
        "error code 0x2310 F2 (FLT 17): Motor Foldback (current)"
    );
    // Without the drive table the standard name applies.
    let d = ErrorCode(0x2310).describe(&[]);
    assert_eq!(d.source, ErrorSource::Standard);
    assert_eq!(d.text, "continuous over-current");
    // 0x8689 is not a standard code: the drive names it; without the table the group does.
    assert_eq!(
        ErrorCode(0x8689).describe(drives::BDHDE_ERRORS).text,
        "Excessive PE Value"
    );
    let g = ErrorCode(0x8689).describe(&[]);
    assert_eq!(g.source, ErrorSource::StandardGroup);
    assert_eq!(g.text, "positioning controller");
    // Standard codes the BDHDE uses with their CiA meaning.
    assert_eq!(ErrorCode(0x3110).describe(&[]).text, "mains over-voltage");
    assert_eq!(ErrorCode(0x3120).describe(&[]).text, "mains under-voltage");
    assert_eq!(
        ErrorCode(0x4310).describe(&[]).text,
        "excess temperature drive"
    );
    assert_eq!(ErrorCode(0x7121).describe(&[]).text, "motor blocked");
    assert_eq!(
        ErrorCode(0x7305).describe(&[]).text,
        "incremental sensor 1 fault"
    );
    assert_eq!(ErrorCode(0x6320).describe(&[]).text, "parameter error");
}

/// MR-J4-TM §7.3.1(3), §7.3.8(1): 0x603F = 0xFF00 + alarm number (SW B2+); 0x1000 generic on SW ≤ B1.
#[test]
fn mr_j4_alarm_codes() {
    let t = drives::MR_J4_ERRORS;
    let d = ErrorCode(0xFF37).describe(t);
    assert_eq!((d.name, d.text), ("AL.37", "Parameter error"));
    assert_eq!(d.class, ErrorClass::DeviceSpecific);
    assert_eq!(ErrorCode(0xFF69).describe(t).name, "AL.69");
    assert_eq!(
        ErrorCode(0xFF86).describe(t).text,
        "Network communication error"
    );
    // An alarm the table does not name falls to the catch-all row; the number is the low byte.
    let d = ErrorCode(0xFF20).describe(t);
    assert_eq!(d.name, "AL.xx");
    // The rows from the MELSERVO-J4 numbering the emulated drive raises.
    assert_eq!(ErrorCode(0xFF52).describe(t).text, "Error excessive");
    assert_eq!(ErrorCode(0xFF35).describe(t).name, "AL.35");
    assert_eq!(ErrorCode(0xFF20).device_specific_low_byte(), Some(0x20));
    assert_eq!(ErrorCode(0x8611).device_specific_low_byte(), None);
    // Old firmware.
    let d = ErrorCode(0x1000).describe(t);
    assert_eq!((d.class, d.text), (ErrorClass::Generic, "generic error"));
}

/// Delta ASDA-A2 (CANopen) alarm table: drive alarms carry standard CiA codes.
#[test]
fn asda_a2_alarm_codes_are_standard() {
    let table = [
        (0x2310, "continuous over-current"), // AL001 overcurrent
        (0x3110, "mains over-voltage"),      // AL002 overvoltage
        (0x3120, "mains under-voltage"),     // AL003 undervoltage
        (0x7122, "motor error or commutation malfunction"), // AL004 motor error
        (0x3210, "DC link over-voltage"),    // AL005 regeneration error
        (0x3230, "load error"),              // AL006 overload
        (0x8400, "velocity speed controller"), // AL007 overspeed
        (0x8611, "following error"),         // AL009 excessive deviation
        (0x7305, "incremental sensor 1 fault"), // AL011 encoder error
        (0x4210, "excess temperature device"), // AL016 IGBT temperature
        (0x7306, "incremental sensor 2 fault"), // AL018 encoder output error
        (0x7510, "serial interface no. 1"),  // AL019 serial comm error
        (0x3130, "phase failure"),           // AL022 input phase loss
        (0x7121, "motor blocked"),           // AL030 motor protection
        (0x3300, "output voltage"),          // AL031 U,V,W wiring
        (0x8130, "life guard or heartbeat error"), // AL170/AL180
        (0x8120, "CAN in error passive mode"), // AL185
    ];
    for (code, text) in table {
        let d = ErrorCode(code).describe(&[]);
        assert_eq!(d.text, text, "0x{code:04X}");
        assert!(
            matches!(d.source, ErrorSource::Standard | ErrorSource::StandardGroup),
            "0x{code:04X}"
        );
    }
    assert_eq!(
        ErrorCode::FOLLOWING_ERROR.standard_name(),
        Some("following error")
    );
    assert_eq!(
        ErrorCode::REFERENCE_LIMIT.standard_name(),
        Some("reference limit")
    );
}

/// BLV-R (CANopen) 0x603F = last alarm + 0xFF00 (§4.5).
#[test]
fn blv_r_alarm_codes() {
    let d = ErrorCode(0xFF30).describe(drives::BLV_R_ERRORS);
    assert_eq!(d.text, "overload");
    assert_eq!(ErrorCode(0xFF30).device_specific_low_byte(), Some(0x30));
    // A code the table does not list falls back to the class.
    let d = ErrorCode(0xFF44).describe(drives::BLV_R_ERRORS);
    assert_eq!(d.source, ErrorSource::StandardGroup);
    assert_eq!(d.class, ErrorClass::DeviceSpecific);
    // CAN-side codes on the same drive are standard.
    assert_eq!(
        ErrorCode(0x8210).describe(drives::BLV_R_ERRORS).text,
        "PDO not processed due to length error"
    );
}

#[test]
fn ranges_and_reserved_values() {
    assert_eq!(ErrorCode(0).class(), ErrorClass::NoError);
    assert!(ErrorCode::NONE.is_none());
    assert_eq!(ErrorCode(0x0001).class(), ErrorClass::Reserved);
    assert_eq!(ErrorCode(0x9000).class(), ErrorClass::External);
    assert_eq!(ErrorCode(0xA000).class(), ErrorClass::Reserved);
    assert_eq!(ErrorCode(0xF0FF).class(), ErrorClass::AdditionalFunctions);
    assert_eq!(ErrorCode(0xF100).class(), ErrorClass::Reserved);
    assert_eq!(ErrorCode(0xFFFF).class(), ErrorClass::DeviceSpecific);
    // Every value describes without panic, and a reserved one says so.
    for v in 0u32..=0xFFFF {
        let d = ErrorCode(v as u16).describe(drives::MR_J4_ERRORS);
        assert!(!d.text.is_empty());
    }
    let d = ErrorCode(0xA123).describe(&[]);
    assert_eq!((d.source, d.text), (ErrorSource::Class, "reserved"));
}

#[test]
fn drive_table_masks() {
    const TABLE: &[ErrorEntry] = &[
        ErrorEntry::exact(0xFF10, "A", "exact"),
        ErrorEntry {
            code: 0xFF00,
            mask: 0xFF00,
            name: "B",
            text: "any FFxx",
        },
    ];
    assert_eq!(ErrorCode(0xFF10).describe(TABLE).name, "A");
    assert_eq!(ErrorCode(0xFF11).describe(TABLE).name, "B");
    assert_eq!(
        ErrorCode(0x2310).describe(TABLE).source,
        ErrorSource::Standard
    );
}
