//! ESI parser errors: kind, exact line/column and message on small inputs; and the consistency
//! checks on small contradicting inputs.

use ecdrive_core::esi::*;
use ecdrive_core::esi::{DeviceChoice, Severity};

/// A minimal file around one device body (the body starts on line 5).
fn with_device(body: &str) -> String {
    format!(
        "<EtherCATInfo>\n\
         <Vendor><Id>#x2</Id><Name>V</Name></Vendor>\n\
         <Descriptions><Devices>\n\
         <Device><Type ProductCode=\"#x10\" RevisionNo=\"1\">D</Type>\n\
         {body}\n\
         </Device>\n\
         </Devices></Descriptions>\n\
         </EtherCATInfo>\n"
    )
}

/// The file's error, else the first device that cannot be read, else the first warning.
fn err(text: &str) -> EsiError {
    match EsiFile::parse(text) {
        Ok(f) => f
            .unreadable
            .first()
            .map(|u| u.error.clone())
            .or_else(|| f.warnings.first().cloned())
            .unwrap_or_else(|| panic!("expected an error for:\n{text}")),
        Err(e) => e,
    }
}

#[test]
fn minimal_file_parses() {
    let f = EsiFile::parse(&with_device("")).unwrap();
    assert_eq!(f.vendor.id, 2);
    assert_eq!(f.devices[0].type_.product_code, 0x10);
    assert_eq!(f.devices[0].type_.revision_no, Some(1));
    assert_eq!(f.devices[0].name, "D", "no <Name>: the type text");
    assert_eq!(f.devices[0].position, Position::new(4, 1));
}

#[test]
fn bad_number_in_element_points_at_the_value() {
    let text = with_device(
        "<RxPdo><Index>#x1600</Index>\n\
         <Entry><Index>#x6040</Index><BitLen>x</BitLen></Entry></RxPdo>",
    );
    let e = err(&text);
    assert_eq!(e.kind, EsiErrorKind::Invalid);
    // Line 6: `<Entry><Index>#x6040</Index><BitLen>` is 36 characters, the `x` is column 37.
    assert_eq!((e.line(), e.column()), (6, 37));
    assert_eq!(
        e.to_string(),
        "line 6, column 37: <Entry> in <RxPdo> 0x1600 has BitLen \"x\": not a number"
    );

    // Blanks around the value: the position is the first non-blank character.
    let e = err(&with_device(
        "<RxPdo><Index>#x1600</Index>\n\
         <Entry><Index>#x6040</Index><BitLen>\n   12a </BitLen></Entry></RxPdo>",
    ));
    assert_eq!((e.line(), e.column()), (7, 4));
    assert!(
        e.message.ends_with("has BitLen \"12a\": not a number"),
        "{e}"
    );
}

#[test]
fn values_with_entities_and_cdata() {
    // Character references and CDATA around a bad value: the position is the text's start.
    let e = err(&with_device(
        "<RxPdo><Index>&#x20;\u{3000}\u{3000}x</Index></RxPdo>",
    ));
    assert_eq!((e.line(), e.column()), (5, 15));
    let e = err(&with_device(
        "<RxPdo><Index><![CDATA[  zz]]></Index></RxPdo>",
    ));
    assert_eq!((e.line(), e.column()), (5, 15));
    // Entities are decoded in values.
    let f = EsiFile::parse(&with_device(
        "<Name>A &amp; B</Name><Sm StartAddress=\"&#x31;\" ControlByte=\"0\">Inputs</Sm>",
    ))
    .unwrap();
    assert_eq!(f.devices[0].name, "A & B");
    assert_eq!(f.devices[0].sync_managers[0].start_address, 1);
}

#[test]
fn out_of_range_numbers() {
    let e = err(&with_device("<TxPdo><Index>#x10000</Index></TxPdo>"));
    assert_eq!((e.line(), e.column()), (5, 15));
    assert_eq!(
        e.message,
        "<TxPdo> has Index \"#x10000\": out of range, expected a 16-bit unsigned number \
         (0..=65535)"
    );
    let e = err(&with_device(
        "<RxPdo><Index>#x1600</Index><Entry><Index>#x6040</Index><SubIndex>256</SubIndex>\
         <BitLen>8</BitLen></Entry></RxPdo>",
    ));
    assert_eq!((e.line(), e.column()), (5, 67));
    assert!(e.message.contains("SubIndex \"256\": out of range"), "{e}");
}

#[test]
fn bad_attribute_points_at_the_value() {
    let e = err(&with_device(
        "<Sm StartAddress=\"#xZZ\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>",
    ));
    assert_eq!(e.kind, EsiErrorKind::Invalid);
    // `<Sm StartAddress="` is 18 characters.
    assert_eq!((e.line(), e.column()), (5, 19));
    assert_eq!(
        e.message,
        "<Sm> 0 in <Device> \"D\" has StartAddress=\"#xZZ\": not a hex number"
    );

    let e = err(&with_device(
        "<RxPdo Fixed=\"yes\"><Index>#x1600</Index></RxPdo>",
    ));
    assert_eq!((e.line(), e.column()), (5, 15));
    assert_eq!(
        e.message,
        "<RxPdo> 0x1600 has Fixed=\"yes\": not a boolean (expected 1, 0, true or false)"
    );
}

#[test]
fn missing_mandatory_parts() {
    // No ProductCode: at the <Type> element.
    let text = "<EtherCATInfo>\n<Vendor><Id>1</Id></Vendor>\n<Descriptions><Devices>\n  \
                <Device>\n    <Type>D</Type>\n  </Device>\n</Devices></Descriptions>\n\
                </EtherCATInfo>";
    let e = err(text);
    assert_eq!(e.kind, EsiErrorKind::Missing);
    assert_eq!((e.line(), e.column()), (5, 5));
    assert_eq!(
        e.message,
        "<Type> of <Device> \"D\" has no ProductCode attribute"
    );

    // No <Vendor>: at the root element.
    let e = err("<?xml version=\"1.0\"?>\n<EtherCATInfo><Descriptions/></EtherCATInfo>");
    assert_eq!(e.kind, EsiErrorKind::Missing);
    assert_eq!((e.line(), e.column()), (2, 1));
    assert_eq!(e.message, "<EtherCATInfo> has no <Vendor>");

    // A PDO entry without BitLen: at the <Entry>.
    let e = err(&with_device(
        "<RxPdo><Index>#x1600</Index>\n  <Entry><Index>#x6040</Index></Entry></RxPdo>",
    ));
    assert_eq!(
        (e.kind, e.line(), e.column()),
        (EsiErrorKind::Missing, 6, 3)
    );
    assert_eq!(e.message, "<Entry> in <RxPdo> 0x1600 has no <BitLen>");

    // A DC mode without AssignActivate.
    let e = err(&with_device("<Dc><OpMode><Name>DC</Name></OpMode></Dc>"));
    assert_eq!((e.line(), e.column()), (5, 5));
    assert_eq!(
        e.message,
        "<OpMode> \"DC\" in <Device> \"D\" has no <AssignActivate>"
    );

    // An InitCmd without a transition.
    let e = err(&with_device(
        "<Mailbox><CoE><InitCmd><Index>#x1C12</Index><Data>00</Data></InitCmd></CoE></Mailbox>",
    ));
    assert_eq!((e.line(), e.column()), (5, 15));
    assert_eq!(
        e.message,
        "<InitCmd> in <CoE> of <Device> \"D\" has no <Transition>"
    );
}

#[test]
fn unknown_keywords() {
    let e = err(&with_device(
        "<Sm StartAddress=\"0\" ControlByte=\"0\">Mailbox</Sm>",
    ));
    assert_eq!((e.line(), e.column()), (5, 38));
    assert_eq!(
        e.message,
        "<Sm> 0 in <Device> \"D\" has type \"Mailbox\": expected MBoxOut, MBoxIn, Outputs or \
         Inputs (read as Inputs, as its ControlByte 0x00 says)"
    );
    let e = err(&with_device(
        "<Mailbox><CoE><InitCmd><Transition>XY</Transition><Index>1</Index><Data>00</Data>\
         </InitCmd></CoE></Mailbox>",
    ));
    assert_eq!((e.line(), e.column()), (5, 36));
    assert!(e.message.contains("has Transition \"XY\""), "{e}");
    let e = err(&with_device(
        "<Profile><Dictionary><Objects><Object><Index>#x6040</Index><Name>CW</Name>\
         <Type>UINT</Type><BitSize>16</BitSize><Flags><Access>rx</Access></Flags></Object>\
         </Objects></Dictionary></Profile>",
    ));
    assert_eq!(e.column(), 128);
    assert_eq!(
        e.message,
        "<Flags> of <Object> 0x6040 has Access \"rx\": expected ro, rw or wo"
    );
    let e = err(&with_device(
        "<Profile><Dictionary><Objects><Object><Index>#x6040</Index><Name>CW</Name>\
         <Type>UINT</Type><BitSize>16</BitSize><Flags><Access WriteRestrictions=\"Init\">rw\
         </Access></Flags></Object></Objects></Dictionary></Profile>",
    ));
    assert!(e.message.contains("WriteRestrictions=\"Init\""), "{e}");
}

#[test]
fn not_an_esi_file() {
    let e = err("<Foo/>");
    assert_eq!(
        (e.kind, e.line(), e.column()),
        (EsiErrorKind::Invalid, 1, 1)
    );
    assert!(e.message.contains("root element is <Foo>"), "{e}");
}

#[test]
fn malformed_xml_gives_the_xml_position() {
    let e = err("<EtherCATInfo>\n  <Vendor>\n</EtherCATInfo>");
    assert_eq!(e.kind, EsiErrorKind::Xml);
    assert_eq!((e.line(), e.column()), (3, 1));
    assert!(e.message.starts_with("malformed XML: "), "{e}");

    let e = err("<EtherCATInfo a=\"1\" a=\"2\"/>");
    assert_eq!(e.kind, EsiErrorKind::Xml);
    assert_eq!(e.line(), 1);

    let e = err("");
    assert_eq!(e.kind, EsiErrorKind::Xml);
    let e = err("<!DOCTYPE x [<!ENTITY a \"b\">]><EtherCATInfo/>");
    assert_eq!(e.kind, EsiErrorKind::Xml);
}

#[test]
fn encoding_errors_and_latin1() {
    // Not UTF-8 and no Latin-1 declaration: position of the bad byte.
    let mut bytes = b"<EtherCATInfo>\n<Ven".to_vec();
    bytes.push(0xE4);
    bytes.extend_from_slice(b"dor/>\n</EtherCATInfo>");
    let e = EsiFile::parse_bytes(&bytes).unwrap_err();
    assert_eq!(
        (e.kind, e.line(), e.column()),
        (EsiErrorKind::Encoding, 2, 5)
    );

    // Declared ISO-8859-1: decoded.
    let mut bytes = b"<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>\n<EtherCATInfo>\
        <Vendor><Id>1</Id><Name>M"
        .to_vec();
    bytes.push(0xFC); // ü
    bytes.extend_from_slice(
        b"ller</Name></Vendor><Descriptions><Devices/></Descriptions></EtherCATInfo>",
    );
    let f = EsiFile::parse_bytes(&bytes).unwrap();
    assert_eq!(f.vendor.name, "Müller");

    // UTF-16 LE with BOM.
    let text = "<EtherCATInfo><Vendor><Id>#x5</Id></Vendor><Descriptions><Devices/>\
                </Descriptions></EtherCATInfo>";
    let mut bytes = vec![0xFF, 0xFE];
    for u in text.encode_utf16() {
        bytes.extend_from_slice(&u.to_le_bytes());
    }
    assert_eq!(EsiFile::parse_bytes(&bytes).unwrap().vendor.id, 5);
    bytes.push(0x00);
    assert_eq!(
        EsiFile::parse_bytes(&bytes).unwrap_err().kind,
        EsiErrorKind::Encoding
    );
}

#[test]
fn errors_from_files_name_the_file() {
    let dir = std::env::temp_dir().join(format!("ecdrive-esi-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.xml");
    std::fs::write(&path, with_device("<RxPdo><Index>zz</Index></RxPdo>")).unwrap();
    let f = EsiFile::from_path(&path).unwrap();
    assert!(f.devices.is_empty());
    let e = f.unreadable[0].error.clone();
    assert_eq!(e.path.as_deref(), Some(path.as_path()));
    assert_eq!(
        e.to_string(),
        format!(
            "{}: line 5, column 15: <RxPdo> has Index \"zz\": not a number",
            path.display()
        )
    );
    let missing = dir.join("missing.xml");
    let e = EsiFile::from_path(&missing).unwrap_err();
    assert_eq!(e.kind, EsiErrorKind::Io);
    assert!(
        e.to_string()
            .starts_with(&format!("{}: cannot read: ", missing.display()))
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn unknown_elements_and_namespaces_are_ignored() {
    let text = "<e:EtherCATInfo xmlns:e=\"urn:x\" xmlns:v=\"urn:vendor\">\
        <e:Vendor><e:Id>7</e:Id><v:Logo>abc</v:Logo></e:Vendor>\
        <e:Descriptions><e:Devices><e:Device><e:Type ProductCode=\"3\">T</e:Type>\
        <v:Whatever><e:Sm>junk</e:Sm></v:Whatever><Info><Anything/></Info>\
        </e:Device></e:Devices></e:Descriptions></e:EtherCATInfo>";
    let f = EsiFile::parse(text).unwrap();
    assert_eq!(f.vendor.id, 7);
    assert!(f.devices[0].sync_managers.is_empty());
}

#[test]
fn identity_numbers_accept_negative_decimals() {
    let text = "<EtherCATInfo><Vendor><Id>-1</Id></Vendor><Descriptions><Devices>\
                <Device><Type ProductCode=\"-2\" RevisionNo=\"0x10\">T</Type></Device>\
                </Devices></Descriptions></EtherCATInfo>";
    let f = EsiFile::parse(text).unwrap();
    assert_eq!(f.vendor.id, 0xFFFF_FFFF);
    assert_eq!(f.devices[0].type_.product_code, 0xFFFF_FFFE);
    assert_eq!(f.devices[0].type_.revision_no, Some(0x10));
}

fn issues(body: &str) -> Vec<String> {
    let f = EsiFile::parse(&with_device(body)).unwrap_or_else(|e| panic!("{e}"));
    f.check().into_iter().map(|i| i.to_string()).collect()
}

#[test]
fn check_finds_contradictions() {
    let sm = "<Fmmu>Outputs</Fmmu><Fmmu>Inputs</Fmmu>\
              <Sm StartAddress=\"#x1100\" ControlByte=\"#x64\" Enable=\"1\" DefaultSize=\"3\">Outputs</Sm>\
              <Sm StartAddress=\"#x1180\" ControlByte=\"#x20\" Enable=\"1\">Inputs</Sm>";
    let entry = |i: &str, bits: u8, dt: &str| {
        format!(
            "<Entry><Index>{i}</Index><SubIndex>0</SubIndex><BitLen>{bits}</BitLen>\
             <DataType>{dt}</DataType></Entry>"
        )
    };
    // Consistent: no issues.
    let ok = format!(
        "{sm}<RxPdo Sm=\"0\"><Index>#x1600</Index>{}{}</RxPdo>",
        entry("#x6040", 16, "UINT"),
        entry("#x6060", 8, "SINT")
    );
    assert_eq!(issues(&ok), Vec::<String>::new());

    // Two default PDOs excluding each other, a PDO on the wrong SM, a size that disagrees with
    // its data type, an exclude of an unknown PDO, an SM size that disagrees with the mapping.
    let bad = format!(
        "{sm}<RxPdo Sm=\"0\"><Index>#x1600</Index><Exclude>#x1601</Exclude>{}</RxPdo>\
         <RxPdo Sm=\"0\"><Index>#x1601</Index><Exclude>#x1605</Exclude>{}</RxPdo>\
         <TxPdo Sm=\"0\"><Index>#x1A00</Index>{}</TxPdo>",
        entry("#x6040", 16, "UINT"),
        entry("#x6060", 16, "SINT"),
        entry("#x6041", 16, "UINT"),
    );
    let got = issues(&bad);
    let want = [
        "RxPDO 0x1600 and 0x1601 are both assigned by default but exclude each other",
        "RxPDO 0x1601 excludes 0x1605, which is not described",
        "RxPDO 0x1601 entry 0x6060:00 has BitLen 16 but DataType INTEGER8 is 8 bits",
        "SM0 DefaultSize 3 differs from the 4 bytes of the default RxPDOs",
        "TxPDO 0x1A00 is assigned to SM0, which is Outputs, not Inputs",
    ];
    for w in want {
        assert!(
            got.iter().any(|g| g.contains(w)),
            "missing {w:?} in {got:#?}"
        );
    }
    assert_eq!(got.len(), want.len(), "{got:#?}");

    // Process data without an FMMU, a mailbox without mailbox SyncManagers.
    let got = issues(
        "<Sm StartAddress=\"#x1100\" ControlByte=\"#x64\" Enable=\"1\">Outputs</Sm>\
         <RxPdo><Index>#x1600</Index></RxPdo><Mailbox><CoE/></Mailbox>",
    );
    assert_eq!(got.len(), 3, "{got:#?}");
    assert!(got[0].contains("has RxPDOs but no <Fmmu>Outputs</Fmmu>"));
    assert!(got[1].contains("has a <Mailbox> but no <Sm>MBoxOut</Sm>"));
}

#[test]
fn check_compares_pdos_with_the_dictionary() {
    let dict = "<Profile><Dictionary><DataTypes>\
        <DataType><Name>DT1600</Name><BitSize>48</BitSize>\
          <SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs></SubItem>\
          <SubItem><SubIdx>1</SubIdx><Name>SubIndex 001</Name><Type>UDINT</Type><BitSize>32</BitSize><BitOffs>16</BitOffs></SubItem>\
        </DataType></DataTypes><Objects>\
        <Object><Index>#x1018</Index><Name>Identity</Name><Type>DT1600</Type><BitSize>48</BitSize>\
          <Info><SubItem><Name>SubIndex 001</Name><Info><DefaultData>03000000</DefaultData></Info></SubItem></Info></Object>\
        <Object><Index>#x1600</Index><Name>RxPDO</Name><Type>DT1600</Type><BitSize>48</BitSize>\
          <Info><SubItem><Name>SubIndex 000</Name><Info><DefaultValue>2</DefaultValue></Info></SubItem>\
          <SubItem><Name>SubIndex 001</Name><Info><DefaultValue>#x60400010</DefaultValue></Info></SubItem></Info></Object>\
        <Object><Index>#x6040</Index><Name>Controlword</Name><Type>UINT</Type><BitSize>16</BitSize>\
          <Flags><Access>rw</Access></Flags></Object>\
        <Object><Index>#x6071</Index><Name>Target torque</Name><Type>INT</Type><BitSize>16</BitSize>\
          <Flags><Access>rw</Access><PdoMapping>R</PdoMapping></Flags></Object>\
        </Objects></Dictionary></Profile>";
    let body = format!(
        "{dict}<Fmmu>Outputs</Fmmu><Sm StartAddress=\"#x1100\" ControlByte=\"#x64\" Enable=\"1\">Outputs</Sm>\
         <RxPdo Sm=\"0\"><Index>#x1600</Index>\
         <Entry><Index>#x6040</Index><SubIndex>0</SubIndex><BitLen>16</BitLen></Entry>\
         <Entry><Index>#x6071</Index><SubIndex>0</SubIndex><BitLen>32</BitLen></Entry>\
         <Entry><Index>#x607A</Index><SubIndex>0</SubIndex><BitLen>32</BitLen></Entry></RxPdo>"
    );
    let got = issues(&body);
    let want = [
        "0x1018:01 default 0x00000003 differs from the vendor <Id> 0x00000002",
        "RxPDO 0x1600 entry 0x6040:00: the dictionary does not mark it mappable as RxPDO",
        "RxPDO 0x1600 entry 0x6071:00 has BitLen 32 but the dictionary says 16",
        "RxPDO 0x1600 entry 0x607A:00 is not in the object dictionary",
        "RxPDO 0x1600 lists 3 entries but 0x1600:00 defaults to 2",
    ];
    for w in want {
        assert!(
            got.iter().any(|g| g.contains(w)),
            "missing {w:?} in {got:#?}"
        );
    }
    assert_eq!(got.len(), want.len(), "{got:#?}");
}

// ---- what real vendor files get wrong, read as the masters people use read it --------------

/// A dictionary of `objects` (and `types`) in the minimal device.
fn with_dictionary(types: &str, objects: &str) -> String {
    with_device(&format!(
        "<Profile><Dictionary><DataTypes>{types}</DataTypes><Objects>{objects}</Objects>\
         </Dictionary></Profile>"
    ))
}

fn resolved(text: &str, index: u16) -> ecdrive_core::esi::ResolvedObject {
    let f = EsiFile::parse(text).unwrap();
    f.devices[0]
        .dictionary()
        .unwrap()
        .resolve(index)
        .unwrap()
        .unwrap()
}

#[test]
fn hex_limits_of_signed_types_are_bit_patterns() {
    // STEPPERONLINE A6: <MinValue>#x80000000</MinValue> on DINT objects; #xFFFC on an INT.
    let text = with_dictionary(
        "",
        "<Object><Index>#x607A</Index><Name>Target position</Name><Type>DINT</Type>\
         <BitSize>32</BitSize><Info><MinValue>#x80000000</MinValue><MaxValue>#x7FFFFFFF\
         </MaxValue></Info></Object>\
         <Object><Index>#x605C</Index><Name>Disable operation option code</Name><Type>INT\
         </Type><BitSize>16</BitSize><Info><MinValue>#xFFFC</MinValue><DefaultValue>-1\
         </DefaultValue></Info></Object>",
    );
    let o = resolved(&text, 0x607A);
    assert!(o.problems.is_empty(), "{:?}", o.problems);
    assert_eq!(
        o.entries[0].min,
        Some(ecdrive_core::od::Value::Int(i64::from(i32::MIN)))
    );
    assert_eq!(
        o.entries[0].max,
        Some(ecdrive_core::od::Value::Int(i64::from(i32::MAX)))
    );
    let o = resolved(&text, 0x605C);
    assert_eq!(o.entries[0].min, Some(ecdrive_core::od::Value::Int(-4)));
    // Decimal out of range is still out of range, and said so, not taken.
    let bad = text.replace("#x80000000", "4294967295");
    let o = resolved(&bad, 0x607A);
    assert_eq!(o.entries[0].min, None);
    assert!(
        o.problems[0].message.contains("out of range for INTEGER32"),
        "{:?}",
        o.problems
    );
    assert_eq!(EsiFile::parse(&bad).unwrap().check().len(), 1);
}

#[test]
fn short_default_data_is_its_low_bytes_and_every_problem_is_listed() {
    // Elmo Gold: <DefaultData>0000</DefaultData> on a UDINT; Bohign: 3 bytes for 0x1000.
    let text = with_dictionary(
        "",
        "<Object><Index>#x2F45</Index><Name>Low voltage</Name><Type>UDINT</Type>\
         <BitSize>32</BitSize><Info><DefaultData>0100</DefaultData></Info></Object>\
         <Object><Index>#x1000</Index><Name>Device type</Name><Type>UDINT</Type>\
         <BitSize>32</BitSize><Info><DefaultData>921004</DefaultData></Info></Object>\
         <Object><Index>#x2000</Index><Name>Odd</Name><Type>UINT</Type>\
         <BitSize>16</BitSize><Info><DefaultData>2</DefaultData></Info></Object>\
         <Object><Index>#x2001</Index><Name>Long</Name><Type>UINT</Type>\
         <BitSize>16</BitSize><Info><DefaultData>01020304</DefaultData></Info></Object>",
    );
    let f = EsiFile::parse(&text).unwrap();
    assert_eq!(
        resolved(&text, 0x2F45).entries[0].default,
        Some(ecdrive_core::od::Value::Uint(1))
    );
    assert_eq!(
        resolved(&text, 0x1000).entries[0].default,
        Some(ecdrive_core::od::Value::Uint(0x04_1092))
    );
    // Not hex data (one digit), and data longer than the type with non-zero bytes past it:
    // left out. All four listed at once, each at its line.
    assert_eq!(resolved(&text, 0x2000).entries[0].default, None);
    assert_eq!(resolved(&text, 0x2001).entries[0].default, None);
    let issues = f.check();
    assert_eq!(issues.len(), 4, "{issues:#?}");
    assert!(
        issues
            .iter()
            .all(|i| i.severity == Severity::Warning && i.position.line == 5)
    );
    // The dictionary a run uses still has every object.
    let dict = ecdrive_core::esi::static_dictionary(&f.devices[0]).unwrap();
    assert_eq!(dict.len(), 4);
}

#[test]
fn byte_arrays_of_any_length_are_one_entry() {
    // Ingenia EVS-NET: <Type>ARRAY [0..511] OF BYTE</Type> (512 elements).
    let types = "<DataType><Name>ARRAY [0..511] OF BYTE</Name><BaseType>BYTE</BaseType>\
                 <BitSize>4096</BitSize><ArrayInfo><LBound>0</LBound><Elements>512</Elements>\
                 </ArrayInfo></DataType>\
                 <DataType><Name>ARRAY [0..15] OF BYTE</Name><BaseType>BYTE</BaseType>\
                 <BitSize>128</BitSize><ArrayInfo><LBound>0</LBound><Elements>16</Elements>\
                 </ArrayInfo></DataType>\
                 <DataType><Name>DT10F3</Name><BitSize>144</BitSize>\
                 <SubItem><SubIdx>0</SubIdx><Name>Count</Name><Type>USINT</Type><BitSize>8\
                 </BitSize><BitOffs>0</BitOffs></SubItem>\
                 <SubItem><SubIdx>6</SubIdx><Name>Message 1</Name><Type>ARRAY [0..15] OF BYTE\
                 </Type><BitSize>128</BitSize><BitOffs>16</BitOffs></SubItem></DataType>";
    let text = with_dictionary(
        types,
        "<Object><Index>#x58B2</Index><Name>Buffer</Name><Type>ARRAY [0..511] OF BYTE</Type>\
         <BitSize>4096</BitSize></Object>\
         <Object><Index>#x10F3</Index><Name>Diagnosis</Name><Type>DT10F3</Type>\
         <BitSize>144</BitSize></Object>",
    );
    let o = resolved(&text, 0x58B2);
    assert_eq!(o.entries.len(), 1);
    assert_eq!(
        o.entries[0].data_type,
        Some(ecdrive_core::od::DataType::OctetString)
    );
    assert_eq!(o.entries[0].bit_len, 4096);
    let o = resolved(&text, 0x10F3);
    assert_eq!(o.entries.iter().map(|e| e.sub).collect::<Vec<_>>(), [0, 6]);
    assert_eq!(o.entries[1].bit_len, 128);
    let f = EsiFile::parse(&text).unwrap();
    assert!(f.check().is_empty(), "{:?}", f.check());
    assert_eq!(
        ecdrive_core::esi::static_dictionary(&f.devices[0])
            .unwrap()
            .len(),
        2
    );
}

#[test]
fn several_devices_in_a_file_are_chosen_by_identity_never_silently() {
    // Elmo: four devices, all <Type>Elmo Drive</Type>.
    let dev = |pc: &str, rev: &str, name: &str| {
        format!(
            "<Device><Type ProductCode=\"{pc}\" RevisionNo=\"{rev}\">Elmo Drive</Type>\
             <Name>{name}</Name></Device>"
        )
    };
    let text = format!(
        "<EtherCATInfo><Vendor><Id>#x9A</Id></Vendor><Descriptions><Devices>{}{}{}{}\
         </Devices></Descriptions></EtherCATInfo>",
        dev("#x00030924", "#x00010420", "Gold bootloader"),
        dev("#x00030924", "#x00010421", "Gold drive"),
        dev("#x00030925", "#x00010420", "Gold twin"),
        dev("#x00030926", "#x00010420", "Gold plus"),
    );
    let f = EsiFile::parse(&text).unwrap();
    let e = f.choose(&DeviceChoice::parse("Elmo Drive")).unwrap_err();
    assert!(
        e.starts_with("4 devices of the file fit \"Elmo Drive\""),
        "{e}"
    );
    assert!(e.contains("\"Gold drive\" 0x00030924:0x00010421"), "{e}");
    let e = f.choose(&DeviceChoice::parse("0x00030924")).unwrap_err();
    assert!(e.starts_with("2 devices of the file fit 0x00030924"), "{e}");
    assert_eq!(
        f.choose(&DeviceChoice::parse("0x00030924:0x00010421")),
        Ok(1)
    );
    assert_eq!(f.choose(&DeviceChoice::parse("0x30926")), Ok(3));
    assert_eq!(f.choose(&DeviceChoice::parse("gold twin")), Ok(2));
    assert!(f.choose(&DeviceChoice::Only).is_err());
    let e = f.choose(&DeviceChoice::parse("0x1")).unwrap_err();
    assert!(
        e.starts_with("the file has no device 0x00000001; it has"),
        "{e}"
    );
}

#[test]
fn deep_nesting_and_huge_files_are_one_line_of_error() {
    let deep = format!(
        "<EtherCATInfo>{}{}</EtherCATInfo>",
        "<a>".repeat(20_000),
        "</a>".repeat(20_000)
    );
    let e = err(&deep);
    assert_eq!(e.kind, EsiErrorKind::Invalid);
    assert!(e.message.contains("nest deeper than 256 levels"), "{e}");
    assert_eq!(e.line(), 1);
    // Comments, CDATA and quoted '>' do not count as nesting.
    let fine = with_device(&format!(
        "<!-- <a><b> -->{}<![CDATA[<x><y>]]><Name a=\"x/>y\">N</Name>",
        "<Info>".repeat(100) + &"</Info>".repeat(100)
    ));
    assert!(EsiFile::parse(&fine).is_ok());
    let huge = " ".repeat(ecdrive_core::esi::MAX_TEXT_BYTES + 1);
    assert!(err(&huge).message.contains("are not read"));
}

#[test]
fn a_device_that_cannot_be_read_leaves_the_others() {
    let text = "<EtherCATInfo><Vendor><Id>2</Id></Vendor><Descriptions><Devices>\
                <Device><Type ProductCode=\"#x1\">A</Type><RxPdo><Index>#x1600</Index>\
                <Entry><Index>#x6040</Index><BitLen>x</BitLen></Entry></RxPdo></Device>\
                <Device><Type ProductCode=\"#x2\">B</Type></Device>\
                </Devices></Descriptions></EtherCATInfo>";
    let f = EsiFile::parse(text).unwrap();
    assert_eq!(f.devices.len(), 1);
    assert_eq!(f.devices[0].type_.product_code, 2);
    assert_eq!(f.unreadable[0].product_code, Some(1));
    let e = f.choose(&DeviceChoice::parse("0x1")).unwrap_err();
    assert!(
        e.contains("cannot be used") && e.contains("BitLen \"x\""),
        "{e}"
    );
    let issues = f.check();
    assert_eq!(issues[0].severity, Severity::Error);
}

// ---- rules found by trying vendor files the project had not seen -----------------------------

/// A VAR object of the minimal dictionary.
fn var(index: &str, name: &str, ty: &str, bits: u16, default: Option<&str>) -> String {
    format!(
        "<Object><Index>{index}</Index><Name>{name}</Name><Type>{ty}</Type>\
         <BitSize>{bits}</BitSize><Info>{}</Info><Flags><Access>rw</Access></Flags></Object>",
        default.map_or(String::new(), |d| format!(
            "<DefaultValue>{d}</DefaultValue>"
        ))
    )
}

/// A CoE drive: controlword, statusword, modes of operation, 0x6502 as given, and `pdos`.
fn drive_with(m6502: Option<&str>, with_6060: bool, pdos: &str) -> String {
    let mut objects = var("#x6040", "Controlword", "UINT", 16, None)
        + &var("#x6041", "Statusword", "UINT", 16, None)
        + &var("#x607A", "Target position", "DINT", 32, None)
        + &var("#x6064", "Position actual value", "DINT", 32, None);
    if with_6060 {
        objects += &var("#x6060", "Modes of operation", "SINT", 8, None);
    }
    if let Some(d) = m6502 {
        objects += &var("#x6502", "Supported drive modes", "UDINT", 32, Some(d));
    }
    with_device(&format!(
        "<Sm StartAddress=\"#x1000\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>\
         <Sm StartAddress=\"#x1080\" ControlByte=\"#x22\" Enable=\"1\">MBoxIn</Sm>\
         <Sm StartAddress=\"#x1100\" ControlByte=\"#x64\" Enable=\"1\">Outputs</Sm>\
         <Sm StartAddress=\"#x1180\" ControlByte=\"#x20\" Enable=\"1\">Inputs</Sm>\
         {pdos}\
         <Mailbox><CoE SdoInfo=\"1\"/></Mailbox>\
         <Profile><Dictionary><DataTypes>\
         <DataType><Name>UINT</Name><BitSize>16</BitSize></DataType>\
         <DataType><Name>DINT</Name><BitSize>32</BitSize></DataType>\
         <DataType><Name>SINT</Name><BitSize>8</BitSize></DataType>\
         <DataType><Name>UDINT</Name><BitSize>32</BitSize></DataType>\
         </DataTypes><Objects>{objects}</Objects></Dictionary></Profile>"
    ))
}

const CSP_PDOS: &str = "<RxPdo Fixed=\"1\" Sm=\"2\"><Index>#x1600</Index><Name>R</Name>\
     <Entry><Index>#x6040</Index><SubIndex>0</SubIndex><BitLen>16</BitLen><Name>cw</Name><DataType>UINT</DataType></Entry>\
     <Entry><Index>#x607A</Index><SubIndex>0</SubIndex><BitLen>32</BitLen><Name>tp</Name><DataType>DINT</DataType></Entry>\
     </RxPdo>\
     <TxPdo Fixed=\"1\" Sm=\"3\"><Index>#x1A00</Index><Name>T</Name>\
     <Entry><Index>#x6041</Index><SubIndex>0</SubIndex><BitLen>16</BitLen><Name>sw</Name><DataType>UINT</DataType></Entry>\
     <Entry><Index>#x6064</Index><SubIndex>0</SubIndex><BitLen>32</BitLen><Name>pa</Name><DataType>DINT</DataType></Entry>\
     <Entry><Index>#x60FD</Index><SubIndex>0</SubIndex><BitLen>32</BitLen><Name>Digital inputs</Name><DataType>UDINT</DataType></Entry>\
     </TxPdo>";

/// Inovance's IS620N file gives 0x6502 a default of 0 (a placeholder its firmware fills): no
/// mode is known from it, as without a default, instead of "supports nothing" and a profile
/// refused with an empty reason.
#[test]
fn a_zero_supported_modes_default_is_no_information() {
    let f = EsiFile::parse(&drive_with(Some("#x0"), true, CSP_PDOS)).unwrap();
    let plan = DrivePlan::new(&f, &f.devices[0]);
    assert!(!plan.modes_from_0x6502);
    assert!(plan.modes.contains(&"csp"), "{:?}", plan.modes);
    assert!(ecdrive_core::drives::esi_profile::from_esi(&f, &f.devices[0], "f.xml").is_ok());
    // A default without any cyclic mode (pp and pv only) says so.
    let f = EsiFile::parse(&drive_with(Some("#x5"), true, CSP_PDOS)).unwrap();
    let e = ecdrive_core::drives::esi_profile::from_esi(&f, &f.devices[0], "f.xml").unwrap_err();
    assert!(e.reason.contains("lists none of csp, csv and cst"), "{e}");
}

/// An Elmo boot device maps 0x60FD in its fixed TxPDO, which its dictionary lacks: the PDO
/// entry describes it, the profile has it mappable (before: "0x60FD:00 does not exist in the
/// dictionary" at start-up). Without 0x6060 the device is no drive to run (a boot loader),
/// `esi show` and the profile agree, and `--esi` never gives it the profile of the drive that
/// shares its product code.
#[test]
fn a_pdo_mapped_object_the_dictionary_lacks_and_a_device_without_0x6060() {
    let f = EsiFile::parse(&drive_with(None, true, CSP_PDOS)).unwrap();
    let p = ecdrive_core::drives::esi_profile::from_esi(&f, &f.devices[0], "f.xml").unwrap();
    let di = p
        .dictionary
        .iter()
        .find(|o| o.index == 0x60FD)
        .expect("0x60FD");
    assert!(
        di.entries[0]
            .access
            .contains(ecdrive_core::od::EntryAccess::TXPDO)
    );
    assert_eq!(di.entries[0].bit_len, 32);

    let f = EsiFile::parse(&drive_with(None, false, CSP_PDOS)).unwrap();
    let why = DrivePlan::new(&f, &f.devices[0])
        .not_a_drive
        .expect("no drive");
    assert!(why.contains("no 0x6060"), "{why}");
    let e = ecdrive_core::drives::esi_profile::from_esi(&f, &f.devices[0], "f.xml").unwrap_err();
    assert!(e.reason.contains("no 0x6060"), "{e}");

    // A folder with the boot loader (revision 1) and the drive (revision 2) of one product.
    let dir = std::env::temp_dir().join(format!("ecdrive-boot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let boot = drive_with(None, false, CSP_PDOS);
    let both = boot.replace(
        "</Device>\n",
        &format!(
            "</Device>\n{}",
            &drive_with(None, true, CSP_PDOS)
                .split("<Device>")
                .nth(1)
                .unwrap()
                .split("</Devices>")
                .next()
                .unwrap()
                .replace("RevisionNo=\"1\"", "RevisionNo=\"2\"")
                .replace("<Device>", "")
        )
        .replacen("<Type", "<Device><Type", 1),
    );
    std::fs::write(dir.join("both.xml"), &both).unwrap();
    let l = ecdrive_core::drives::esi_profile::load_dir(&dir).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(l.profiles.len(), 1, "{:?}", l.skipped);
    assert_eq!(l.profiles[0].revision, 2);
    assert_eq!(l.not_drives, vec![(2, 0x10, 1)]);
    let boot_device = ecdrive_ethercat::startup::DeviceInfo {
        position: 0,
        address: 0x1000,
        alias: 0,
        name: "D".into(),
        vendor_id: 2,
        product_code: 0x10,
        revision: 1,
        serial: 0,
        dc: true,
        profile: None,
        coe: true,
        device_type: None,
        found: None,
    };
    assert!(
        ecdrive_ethercat::startup::esi_profile_for(&l.profiles, &l.not_drives, &boot_device)
            .is_none()
    );
    let unknown_revision = ecdrive_ethercat::startup::DeviceInfo {
        revision: 3,
        ..boot_device.clone()
    };
    assert!(
        ecdrive_ethercat::startup::esi_profile_for(&l.profiles, &l.not_drives, &unknown_revision)
            .is_some()
    );
}

/// An SMC EX250 file labels its input SM `Outputs`, with ControlByte 0x00 (the master reads)
/// and its TxPDO assigned to it: read as Inputs, noted; a label that only one of the two
/// contradicts stays.
#[test]
fn an_sm_labelled_against_its_control_byte_and_pdos() {
    let body = "<Sm StartAddress=\"#x0f00\" ControlByte=\"#x46\" Enable=\"9\">Outputs</Sm>\
        <Sm StartAddress=\"#x1000\" ControlByte=\"#x0\" Enable=\"1\">Outputs</Sm>\
        <RxPdo Fixed=\"1\" Sm=\"0\"><Index>#x1600</Index><Name>O</Name>\
        <Entry><Index>#x7000</Index><SubIndex>1</SubIndex><BitLen>8</BitLen><Name>b</Name><DataType>USINT</DataType></Entry></RxPdo>\
        <TxPdo Fixed=\"1\" Sm=\"1\"><Index>#x1A00</Index><Name>I</Name>\
        <Entry><Index>#x6000</Index><SubIndex>1</SubIndex><BitLen>8</BitLen><Name>b</Name><DataType>USINT</DataType></Entry></TxPdo>";
    let f = EsiFile::parse(&with_device(body)).unwrap();
    let kinds: Vec<&str> = f.devices[0]
        .sync_managers
        .iter()
        .map(|s| s.kind.name())
        .collect();
    assert_eq!(kinds, ["Outputs", "Inputs"]);
    assert!(
        f.warnings
            .iter()
            .any(|w| w.to_string().contains("read as Inputs")),
        "{:?}",
        f.warnings
    );
    // Without the TxPDO on it, the label stays.
    let f = EsiFile::parse(&with_device(&body.replace("Sm=\"1\"", "Sm=\"5\""))).unwrap();
    assert_eq!(f.devices[0].sync_managers[1].kind.name(), "Outputs");
}
