#!/usr/bin/env python3
"""Writes the three vendor-shaped drive ESI files of tests/data/esi/ (issue "Any CiA 402 drive
from its vendor's ESI file"). They are not ecdrive's two drives and not real products: vendor
IDs 0x00000E01-0x00000E03 are ecdrive's test values, not ETG-assigned. Each file is shaped the
way vendors write them (ETG.2000): a dictionary with its data types, PDOs with Fixed, Mandatory
and Exclude, SyncManagers, DC op modes with cycle factors, CoE details and <InitCmd>s.

  Nordwind_ND40.xml     fixed PDOs, one per cyclic mode, alternatives excluded by <Exclude>
  Kestrel_KS2.xml       configurable PDOs, 10 entries per mapping object at most
  Taiga_TX7.xml         fixed PDOs, read-only 0x1C32, InitCmds that set the cycle time
                        through a vendor object (0x2010) and the mode, in file order

Run it from the repository root; the files are committed, this script is how they were made.
"""
import os

HERE = os.path.dirname(os.path.abspath(__file__))

TYPES = {  # name: bits
    "BOOL": 1, "SINT": 8, "USINT": 8, "INT": 16, "UINT": 16, "DINT": 32, "UDINT": 32,
}

def dt_record(name, subs):
    """subs: list of (subidx, name, type, bits, access, pdo)"""
    out = [f"              <DataType>", f"                <Name>{name}</Name>"]
    off, items = 0, []
    for (si, n, t, b, acc, pdo) in subs:
        if si == 1:
            off = 16
        items.append((si, n, t, b, off, acc, pdo))
        off += b
    out.append(f"                <BitSize>{off}</BitSize>")
    for (si, n, t, b, o, acc, pdo) in items:
        flags = f"<Access>{acc}</Access>" + (f"<PdoMapping>{pdo}</PdoMapping>" if pdo else "")
        out += [
            "                <SubItem>",
            f"                  <SubIdx>{si}</SubIdx>",
            f"                  <Name>{n}</Name>",
            f"                  <Type>{t}</Type>",
            f"                  <BitSize>{b}</BitSize>",
            f"                  <BitOffs>{o}</BitOffs>",
            f"                  <Flags>{flags}</Flags>",
            "                </SubItem>",
        ]
    out.append("              </DataType>")
    return out

def obj_var(index, name, typ, bits, access, pdo=None, default=None):
    flags = f"<Access>{access}</Access>" + (f"<PdoMapping>{pdo}</PdoMapping>" if pdo else "")
    info = f"<Info><DefaultData>{default}</DefaultData></Info>" if default else ""
    return [
        "              <Object>",
        f"                <Index>#x{index:04x}</Index>",
        f"                <Name>{name}</Name>",
        f"                <Type>{typ}</Type>",
        f"                <BitSize>{bits}</BitSize>",
        f"                {info}" if info else None,
        f"                <Flags>{flags}</Flags>",
        "              </Object>",
    ]

def obj_rec(index, name, typ, bits, subs_defaults=None):
    out = [
        "              <Object>",
        f"                <Index>#x{index:04x}</Index>",
        f"                <Name>{name}</Name>",
        f"                <Type>{typ}</Type>",
        f"                <BitSize>{bits}</BitSize>",
    ]
    if subs_defaults:
        out.append("                <Info>")
        for (n, d) in subs_defaults:
            out.append(f"                  <SubItem><Name>{n}</Name><Info><DefaultData>{d}</DefaultData></Info></SubItem>")
        out.append("                </Info>")
    out.append("              </Object>")
    return out

def le(v, n):
    return v.to_bytes(n, "little", signed=v < 0).hex()

def entry(i, s, b, n, t):
    if i == 0:
        return [f"          <Entry><Index>#x0</Index><BitLen>{b}</BitLen></Entry>"]
    return [
        "          <Entry>",
        f"            <Index>#x{i:04x}</Index>",
        f"            <SubIndex>{s}</SubIndex>",
        f"            <BitLen>{b}</BitLen>",
        f"            <Name>{n}</Name>",
        f"            <DataType>{t}</DataType>",
        "          </Entry>",
    ]

CIA = {  # index: (name, type, bits, access, pdo)
    0x6040: ("Controlword", "UINT", 16, "rw", "R"),
    0x6041: ("Statusword", "UINT", 16, "ro", "T"),
    0x6060: ("Modes of operation", "SINT", 8, "rw", "R"),
    0x6061: ("Modes of operation display", "SINT", 8, "ro", "T"),
    0x6064: ("Position actual value", "DINT", 32, "ro", "T"),
    0x606C: ("Velocity actual value", "DINT", 32, "ro", "T"),
    0x6077: ("Torque actual value", "INT", 16, "ro", "T"),
    0x607A: ("Target position", "DINT", 32, "rw", "R"),
    0x60FF: ("Target velocity", "DINT", 32, "rw", "R"),
    0x6071: ("Target torque", "INT", 16, "rw", "R"),
    0x603F: ("Error code", "UINT", 16, "ro", "T"),
    0x605A: ("Quick stop option code", "INT", 16, "rw", None),
    0x6502: ("Supported drive modes", "UDINT", 32, "ro", None),
}

def device(vendor_id, product, revision, order, name, pdos, sync, init_cmds, extra_objs,
           pdo_config, map_entries, dc_modes, comments, encoder=None):
    """pdos: list of (dir, index, name, sm, fixed, mandatory, excludes, entries)"""
    L = []
    L.append('      <Device Physics="YY">')
    L.append(f'        <Type ProductCode="#x{product:08x}" RevisionNo="#x{revision:08x}">{order}</Type>')
    L.append(f'        <Name LcId="1033">{name}</Name>')
    L.append('        <GroupType>Drives</GroupType>')
    L.append('        <Profile>')
    L.append('          <ProfileNo>402</ProfileNo>')
    L.append('          <AddInfo>2</AddInfo>')
    L.append('          <Dictionary>')
    L.append('            <DataTypes>')
    for t, b in TYPES.items():
        L += ["              <DataType>", f"                <Name>{t}</Name>", f"                <BitSize>{b}</BitSize>", "              </DataType>"]
    L += ["              <DataType>", "                <Name>STRING(8)</Name>", "                <BitSize>64</BitSize>", "              </DataType>"]
    L += dt_record("DT1018", [(0, "SubIndex 000", "USINT", 8, "ro", None)] + [
        (i, n, "UDINT", 32, "ro", None) for i, n in
        [(1, "Vendor ID"), (2, "Product code"), (3, "Revision"), (4, "Serial number")]])
    # mapping objects: map_entries entries
    L += dt_record("DTPDOMAP", [(0, "SubIndex 000", "USINT", 8, "rw" if pdo_config else "ro", None)] + [
        (i, f"SubIndex {i:03d}", "UDINT", 32, "rw" if pdo_config else "ro", None) for i in range(1, map_entries + 1)])
    L += dt_record("DTASSIGN", [(0, "SubIndex 000", "USINT", 8, "rw", None)] + [
        (i, f"SubIndex {i:03d}", "UINT", 16, "rw", None) for i in range(1, 4)])
    sync_access = sync["cycle_access"]
    L += dt_record("DT1C32", [(0, "SubIndex 000", "USINT", 8, "ro", None),
                             (1, "Synchronization Type", "UINT", 16, sync["type_access"], None),
                             (2, "Cycle Time", "UDINT", 32, sync_access, None),
                             (3, "Shift Time", "UDINT", 32, "ro", None),
                             (4, "Synchronization Types supported", "UINT", 16, "ro", None),
                             (5, "Minimum Cycle Time", "UDINT", 32, "ro", None)])
    if encoder:
        L += dt_record("DT608F", [(0, "SubIndex 000", "USINT", 8, "ro", None),
                                  (1, "Encoder increments", "UDINT", 32, "rw", None),
                                  (2, "Motor revolutions", "UDINT", 32, "rw", None)])
    L.append('            </DataTypes>')
    L.append('            <Objects>')
    objs = []
    objs += obj_var(0x1000, "Device type", "UDINT", 32, "ro", default=le(0x00020192, 4))
    objs += obj_var(0x1008, "Device name", "STRING(8)", 64, "ro")
    objs += obj_rec(0x1018, "Identity", "DT1018", 144,
                    [("SubIndex 000", "04"), ("Vendor ID", le(vendor_id, 4)),
                     ("Product code", le(product, 4)), ("Revision", le(revision, 4)),
                     ("Serial number", "00000000")])
    for (d, idx, n, sm, fixed, mand, exc, ents) in pdos:
        defaults = [("SubIndex 000", le(len([e for e in ents]), 1))]
        for i, (ei, es, eb, en, et) in enumerate(ents):
            defaults.append((f"SubIndex {i+1:03d}", le(ei << 16 | es << 8 | eb, 4)))
        objs += obj_rec(idx, n, "DTPDOMAP", 16 + 32 * map_entries, defaults)
    for (sm_no, idx) in [(2, 0x1C12), (3, 0x1C13)]:
        d = "Rx" if sm_no == 2 else "Tx"
        assigned = [p[1] for p in pdos if p[0] == d and p[3] == sm_no]
        defaults = [("SubIndex 000", le(len(assigned), 1))] + [
            (f"SubIndex {i+1:03d}", le(a, 2)) for i, a in enumerate(assigned)]
        objs += obj_rec(idx, "Sync manager %d PDO assignment" % sm_no, "DTASSIGN", 64, defaults)
    for idx, nm in [(0x1C32, "SM output parameter"), (0x1C33, "SM input parameter")]:
        objs += obj_rec(idx, nm, "DT1C32", 176,
                        [("SubIndex 000", "05"), ("Synchronization Type", le(sync["type"], 2)),
                         ("Cycle Time", le(sync["cycle_ns"], 4)), ("Shift Time", "00000000"),
                         ("Synchronization Types supported", le(0x0005, 2)),
                         ("Minimum Cycle Time", le(sync["min_ns"], 4))])
    for idx in sorted(CIA):
        n, t, b, acc, pdo = CIA[idx]
        default = le(sync["modes_supported"], 4) if idx == 0x6502 else None
        objs += obj_var(idx, n, t, b, acc, pdo, default)
    for (idx, n, t, b, acc, default) in extra_objs:
        objs += obj_var(idx, n, t, b, acc, None, default)
    if encoder:
        (inc, revs) = encoder
        objs += obj_rec(0x608F, "Position encoder resolution", "DT608F", 80,
                        [("SubIndex 000", "02"), ("Encoder increments", le(inc, 4)),
                         ("Motor revolutions", le(revs, 4))])
    L += [o for o in objs if o is not None]
    L.append('            </Objects>')
    L.append('          </Dictionary>')
    L.append('        </Profile>')
    L.append('        <Fmmu>Outputs</Fmmu>')
    L.append('        <Fmmu>Inputs</Fmmu>')
    L.append('        <Fmmu>MBoxState</Fmmu>')
    L.append('        <Sm DefaultSize="128" StartAddress="#x1000" ControlByte="#x26" Enable="1">MBoxOut</Sm>')
    L.append('        <Sm DefaultSize="128" StartAddress="#x1080" ControlByte="#x22" Enable="1">MBoxIn</Sm>')
    L.append('        <Sm StartAddress="#x1100" ControlByte="#x64" Enable="1">Outputs</Sm>')
    L.append('        <Sm StartAddress="#x1400" ControlByte="#x20" Enable="1">Inputs</Sm>')
    for c in comments:
        L.append(f'        <!-- {c} -->')
    for (d, idx, n, sm, fixed, mand, exc, ents) in pdos:
        attrs = ""
        if fixed:
            attrs += ' Fixed="1"'
        if mand:
            attrs += ' Mandatory="1"'
        if sm is not None:
            attrs += f' Sm="{sm}"'
        tag = "RxPdo" if d == "Rx" else "TxPdo"
        L.append(f'        <{tag}{attrs}>')
        L.append(f'          <Index>#x{idx:04x}</Index>')
        L.append(f'          <Name>{n}</Name>')
        for e in exc:
            L.append(f'          <Exclude>#x{e:04x}</Exclude>')
        for (ei, es, eb, en, et) in ents:
            L += entry(ei, es, eb, en, et)
        L.append(f'        </{tag}>')
    L.append('        <Mailbox DataLinkLayer="true">')
    L.append(f'          <CoE SdoInfo="true" PdoAssign="true" PdoConfig="{"true" if pdo_config else "false"}" CompleteAccess="false" SegmentedSdo="true">')
    for cmd in init_cmds:
        (trans, idx, sub, data, comment) = cmd[:5]
        extra = cmd[5] if len(cmd) > 5 else {}
        fixed = ' Fixed="true"' if extra.get("fixed") else ''
        L.append(f'            <InitCmd{fixed}>')
        for t in trans:
            L.append(f'              <Transition>{t}</Transition>')
        L.append(f'              <Index>#x{idx:04x}</Index>')
        L.append(f'              <SubIndex>{sub}</SubIndex>')
        L.append(f'              <Data>{data}</Data>')
        L.append(f'              <Comment>{comment}</Comment>')
        # Elements of the network description (ETG.2100) that vendor files carry too.
        if "timeout" in extra:
            L.append(f'              <Timeout>{extra["timeout"]}</Timeout>')
        if "retries" in extra:
            L.append(f'              <Retries>{extra["retries"]}</Retries>')
        if extra.get("disabled"):
            L.append('              <Disabled>true</Disabled>')
        L.append('            </InitCmd>')
    L.append('          </CoE>')
    L.append('        </Mailbox>')
    L.append('        <Dc>')
    for (nm, desc, aa, f0, shift) in dc_modes:
        L.append('          <OpMode>')
        L.append(f'            <Name>{nm}</Name>')
        L.append(f'            <Desc>{desc}</Desc>')
        L.append(f'            <AssignActivate>#x{aa:04x}</AssignActivate>')
        if f0 is not None:
            L.append(f'            <CycleTimeSync0 Factor="{f0}">0</CycleTimeSync0>')
            L.append(f'            <ShiftTimeSync0>{shift}</ShiftTimeSync0>')
        L.append('          </OpMode>')
    L.append('        </Dc>')
    L.append('        <Eeprom>')
    L.append('          <ByteSize>2048</ByteSize>')
    L.append('          <ConfigData>080C00006400000000000000</ConfigData>')
    L.append('        </Eeprom>')
    L.append('      </Device>')
    return L

def write(fname, vendor_id, vendor_name, comment, dev):
    L = ['<?xml version="1.0" encoding="UTF-8"?>',
         f'<!-- {comment} -->',
         '<EtherCATInfo xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" Version="1.6" xsi:noNamespaceSchemaLocation="EtherCATInfo.xsd">',
         '  <Vendor>', f'    <Id>#x{vendor_id:08x}</Id>', f'    <Name LcId="1033">{vendor_name}</Name>', '  </Vendor>',
         '  <Descriptions>', '    <Groups>', '      <Group>', '        <Type>Drives</Type>',
         '        <Name LcId="1033">Servo drives</Name>', '      </Group>', '    </Groups>', '    <Devices>']
    L += dev
    L += ['    </Devices>', '  </Descriptions>', '</EtherCATInfo>', '']
    with open(os.path.join(HERE, fname), "w") as f:
        f.write("\n".join(L))

CW = (0x6040, 0, 16, "Controlword", "UINT")
SW = (0x6041, 0, 16, "Statusword", "UINT")
MODE = (0x6060, 0, 8, "Modes of operation", "SINT")
MODED = (0x6061, 0, 8, "Modes of operation display", "SINT")
TPOS = (0x607A, 0, 32, "Target position", "DINT")
TVEL = (0x60FF, 0, 32, "Target velocity", "DINT")
TTQ = (0x6071, 0, 16, "Target torque", "INT")
APOS = (0x6064, 0, 32, "Position actual value", "DINT")
AVEL = (0x606C, 0, 32, "Velocity actual value", "DINT")
ATQ = (0x6077, 0, 16, "Torque actual value", "INT")
ERR = (0x603F, 0, 16, "Error code", "UINT")
PAD8 = (0, 0, 8, "", "")
CSP_CSV_CST = (1 << 7) | (1 << 8) | (1 << 9)  # 0x6502 bits 7-9: csp, csv, cst

DC = [("DC", "DC SYNC0", 0x0300, 1, 0), ("FreeRun", "Free run", 0x0000, None, 0)]

write("Nordwind_ND40.xml", 0x0E01, "Nordwind Antriebstechnik (ecdrive test vendor)",
      "Vendor-shaped ESI written for ecdrive's tests: fixed PDOs, one RxPDO per cyclic mode, "
      "alternatives excluded by Exclude. Not a real product.",
      device(0x0E01, 0x00000040, 0x00010003, "ND40", "ND40 servo drive (csp/csv/cst)",
             [("Rx", 0x1600, "Outputs csp", 2, True, False, [0x1601, 0x1602], [CW, MODE, PAD8, TPOS]),
              ("Rx", 0x1601, "Outputs csv", None, True, False, [0x1600, 0x1602], [CW, MODE, PAD8, TVEL]),
              ("Rx", 0x1602, "Outputs cst", None, True, False, [0x1600, 0x1601], [CW, MODE, PAD8, TTQ]),
              ("Tx", 0x1A00, "Inputs", 3, True, True, [], [SW, MODED, PAD8, APOS, AVEL, ATQ, ERR])],
             {"type": 2, "type_access": "rw", "cycle_access": "rw", "cycle_ns": 1000000,
              "min_ns": 250000, "modes_supported": CSP_CSV_CST},
             [(["PS"], 0x605A, 0, "0200", "quick stop option: ramp, then Switch on disabled")],
             [], False, 8, DC,
             ["PDOs: one fixed RxPDO per cyclic mode; they exclude each other"]))

write("Kestrel_KS2.xml", 0x0E02, "Kestrel Motion (ecdrive test vendor)",
      "Vendor-shaped ESI written for ecdrive's tests: configurable PDOs, at most 10 entries per "
      "mapping object (the dictionary's 0x1600/0x1A00 have sub-indices 1-10). Not a real product.",
      device(0x0E02, 0x000000B2, 0x00000002, "KS2", "KS2 compact servo",
             [("Rx", 0x1600, "RxPDO 1", 2, False, False, [], [CW, TPOS]),
              ("Rx", 0x1601, "RxPDO 2", None, False, False, [], []),
              ("Tx", 0x1A00, "TxPDO 1", 3, False, False, [], [SW, APOS]),
              ("Tx", 0x1A01, "TxPDO 2", None, False, False, [], [])],
             {"type": 2, "type_access": "rw", "cycle_access": "rw", "cycle_ns": 2000000,
              "min_ns": 500000, "modes_supported": CSP_CSV_CST},
             [], [], True, 10, DC,
             ["PDOs: configurable, 10 entries per mapping object",
              "0x608F: 8388608 increments per revolution (a 23-bit encoder)"],
             encoder=(8388608, 1)))

write("Taiga_TX7.xml", 0x0E03, "Taiga Drives (ecdrive test vendor)",
      "Vendor-shaped ESI written for ecdrive's tests: fixed PDOs, read-only 0x1C32 (the cycle "
      "time is set through the vendor object 0x2010 by InitCmds), several InitCmds in file "
      "order. Not a real product.",
      device(0x0E03, 0x00070007, 0x00000101, "TX7", "TX7 servo amplifier",
             [("Rx", 0x1600, "Outputs", 2, True, True, [], [CW, MODE, PAD8, TPOS, TVEL, TTQ, (0, 0, 16, "", "")]),
              ("Tx", 0x1A00, "Inputs", 3, True, True, [], [SW, MODED, PAD8, APOS, AVEL, ATQ, ERR])],
             {"type": 2, "type_access": "ro", "cycle_access": "ro", "cycle_ns": 1000000,
              "min_ns": 1000000, "modes_supported": CSP_CSV_CST},
             [(["PS"], 0x2010, 0, "e803", "cycle time 1000 us (vendor object; 0x1C32:02 is read-only)",
               {"fixed": True, "timeout": 3000, "retries": 1}),
              (["PS"], 0x2011, 0, "01", "synchronise to SYNC0"),
              (["PS"], 0x2FFF, 0, "01", "factory test mode (disabled: never sent)",
               {"disabled": True}),
              (["PS", "SO"], 0x6060, 0, "08", "mode of operation: csp")],
             [(0x2010, "Cycle time (us)", "UINT", 16, "rw", le(1000, 2)),
              (0x2011, "Sync source", "USINT", 8, "rw", "00")],
             False, 8, [("DC", "DC SYNC0", 0x0300, 1, 0)],
             ["PDOs: fixed; 0x1C32 read-only; the cycle time is set through 0x2010 (InitCmd)"]))
