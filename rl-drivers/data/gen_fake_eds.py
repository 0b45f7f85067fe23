#!/usr/bin/env python3
"""Writes rl-fake-cia402.eds: the CiA 306 EDS of rl-rs's fake CiA 402 drive (rl_drivers::fake::
cia402_drive) — the mandatory CiA 301 objects, 4 RPDOs and 4 TPDOs, and the CiA 402 objects a
cyclic synchronous master uses. Run from this directory: python3 gen_fake_eds.py"""

VAR, ARRAY, RECORD = 0x7, 0x8, 0x9
BOOL, I8, I16, I32, U8, U16, U32, VSTR = 0x1, 0x2, 0x3, 0x4, 0x5, 0x6, 0x7, 0x9

objects = []  # (index, name, type, subs) with subs [(sub, name, dtype, access, default, pdo)]


def var(index, name, dtype, access, default, pdo=0):
    objects.append((index, name, VAR, [(0, name, dtype, access, default, pdo)]))


def rec(index, name, subs, otype=RECORD):
    objects.append((index, name, otype, subs))


var(0x1000, "Device type", U32, "ro", "0x00020192")
var(0x1001, "Error register", U8, "ro", "0", 1)
var(0x1005, "COB-ID SYNC", U32, "rw", "0x00000080")
var(0x1006, "Communication cycle period", U32, "rw", "0")
var(0x1008, "Manufacturer device name", VSTR, "const", "rl-rs fake CiA 402 drive")
var(0x1009, "Manufacturer hardware version", VSTR, "const", "1.0")
var(0x100A, "Manufacturer software version", VSTR, "const", "0.1.0")
var(0x1017, "Producer heartbeat time", U16, "rw", "0")
rec(0x1018, "Identity object", [
    (0, "Highest sub-index supported", U8, "const", "4", 0),
    (1, "Vendor-ID", U32, "ro", "0x00000E1D", 0),
    (2, "Product code", U32, "ro", "0x00000402", 0),
    (3, "Revision number", U32, "ro", "0x00010000", 0),
    (4, "Serial number", U32, "ro", "$NODEID+0x52520000", 0),
])
for k in range(4):
    rec(0x1400 + k, f"RPDO{k + 1} communication parameter", [
        (0, "Highest sub-index supported", U8, "const", "2", 0),
        (1, "COB-ID used by RPDO", U32, "rw", f"$NODEID+0x{0x200 + 0x100 * k:X}" if k == 0 else f"$NODEID+0x{0x80000200 + 0x100 * k:X}", 0),
        (2, "Transmission type", U8, "rw", "255", 0),
    ])
for k in range(4):
    rec(0x1600 + k, f"RPDO{k + 1} mapping parameter", [
        (0, "Number of mapped objects", U8, "rw", "2" if k == 0 else "0", 0),
    ] + [(s, f"Mapped object {s}", U32, "rw",
          {(0, 1): "0x60400010", (0, 2): "0x607A0020"}.get((k, s), "0x00000000"), 0) for s in range(1, 9)])
for k in range(4):
    rec(0x1800 + k, f"TPDO{k + 1} communication parameter", [
        (0, "Highest sub-index supported", U8, "const", "5", 0),
        (1, "COB-ID used by TPDO", U32, "rw", f"$NODEID+0x{0x40000180 + 0x100 * k:X}" if k == 0 else f"$NODEID+0x{0xC0000180 + 0x100 * k:X}", 0),
        (2, "Transmission type", U8, "rw", "255", 0),
        (3, "Inhibit time", U16, "rw", "0", 0),
        (5, "Event timer", U16, "rw", "0", 0),
    ])
for k in range(4):
    rec(0x1A00 + k, f"TPDO{k + 1} mapping parameter", [
        (0, "Number of mapped objects", U8, "rw", "2" if k == 0 else "0", 0),
    ] + [(s, f"Mapped object {s}", U32, "rw",
          {(0, 1): "0x60410010", (0, 2): "0x60640020"}.get((k, s), "0x00000000"), 0) for s in range(1, 9)])

var(0x603F, "Error code", U16, "ro", "0", 1)
var(0x6040, "Controlword", U16, "rww", "0", 1)
var(0x6041, "Statusword", U16, "ro", "0", 1)
var(0x605A, "Quick stop option code", I16, "rw", "2")
var(0x6060, "Modes of operation", I8, "rw", "8", 1)
var(0x6061, "Modes of operation display", I8, "ro", "0", 1)
var(0x6064, "Position actual value", I32, "ro", "0", 1)
var(0x6065, "Following error window", U32, "rw", "0")
var(0x606C, "Velocity actual value", I32, "ro", "0", 1)
var(0x6071, "Target torque", I16, "rww", "0", 1)
var(0x6072, "Max torque", U16, "rw", "3000", 1)
var(0x6076, "Motor rated torque", U32, "rw", "1000")
var(0x6077, "Torque actual value", I16, "ro", "0", 1)
var(0x607A, "Target position", I32, "rww", "0", 1)
rec(0x607D, "Software position limit", [
    (0, "Highest sub-index supported", U8, "const", "2", 0),
    (1, "Min position limit", I32, "rw", "0", 0),
    (2, "Max position limit", I32, "rw", "0", 0),
], ARRAY)
var(0x607F, "Max profile velocity", U32, "rw", "0")
# The factor group (CiA 402-2 §6.3): encoder increments per motor revolution, motor revolutions per
# shaft revolution, position units per shaft revolution. These defaults are the fake's own
# (2^20 counts, direct drive, position unit = increment); the fake writes its configured units
# over them, or removes the three objects when told to refuse them. Read-only here: the fake's
# motor does not rescale, so a write is refused rather than silently ignored.
rec(0x608F, "Position encoder resolution", [
    (0, "Highest sub-index supported", U8, "const", "2", 0),
    (1, "Encoder increments", U32, "ro", "1048576", 0),
    (2, "Motor revolutions", U32, "ro", "1", 0),
], ARRAY)
rec(0x6091, "Gear ratio", [
    (0, "Highest sub-index supported", U8, "const", "2", 0),
    (1, "Motor revolutions", U32, "ro", "1", 0),
    (2, "Shaft revolutions", U32, "ro", "1", 0),
], ARRAY)
rec(0x6092, "Feed constant", [
    (0, "Highest sub-index supported", U8, "const", "2", 0),
    (1, "Feed", U32, "ro", "1048576", 0),
    (2, "Shaft revolutions", U32, "ro", "1", 0),
], ARRAY)
var(0x60B1, "Velocity offset", I32, "rww", "0", 1)
var(0x60B2, "Torque offset", I16, "rww", "0", 1)
rec(0x60C2, "Interpolation time period", [
    (0, "Highest sub-index supported", U8, "const", "2", 0),
    (1, "Interpolation time period value", U8, "rw", "1", 0),
    (2, "Interpolation time index", I8, "rw", "-3", 0),
])
var(0x60F4, "Following error actual value", I32, "ro", "0", 1)
var(0x60FF, "Target velocity", I32, "rww", "0", 1)
var(0x6502, "Supported drive modes", U32, "ro", "0x00000380")

mandatory = [0x1000, 0x1001, 0x1018]
optional = [o[0] for o in objects if o[0] not in mandatory]

out = []
w = out.append
w("[FileInfo]")
w("FileName=rl-fake-cia402.eds")
w("FileVersion=1")
w("FileRevision=0")
w("EDSVersion=4.0")
w("Description=rl-rs fake CiA 402 servo drive (a simulation on the wire, for tests)")
w("CreationTime=12:00PM")
w("CreationDate=12-01-2026")
w("CreatedBy=rl-rs")
w("ModificationTime=12:00PM")
w("ModificationDate=12-01-2026")
w("ModifiedBy=rl-rs")
w("")
w("[DeviceInfo]")
w("VendorName=rl-rs")
w("VendorNumber=0x00000E1D")
w("ProductName=rl-rs fake CiA 402 drive")
w("ProductNumber=0x00000402")
w("RevisionNumber=0x00010000")
w("OrderCode=rl-fake-cia402")
for rate in (10, 20, 50, 125, 250, 500, 800, 1000):
    w(f"BaudRate_{rate}=1")
w("SimpleBootUpMaster=0")
w("SimpleBootUpSlave=1")
w("Granularity=8")
w("DynamicChannelsSupported=0")
w("GroupMessaging=0")
w("NrOfRXPDO=4")
w("NrOfTXPDO=4")
w("LSS_Supported=0")
w("")
w("[DummyUsage]")
for d in range(1, 8):
    w(f"Dummy{d:04X}=0")
w("")
for section, indexes in (("MandatoryObjects", mandatory), ("OptionalObjects", optional)):
    w(f"[{section}]")
    w(f"SupportedObjects={len(indexes)}")
    for i, index in enumerate(indexes, 1):
        w(f"{i}=0x{index:04X}")
    w("")
w("[ManufacturerObjects]")
w("SupportedObjects=0")
w("")


def entry(section, name, dtype, access, default, pdo, otype=None):
    w(f"[{section}]")
    w(f"ParameterName={name}")
    if otype is not None:
        w(f"ObjectType=0x{otype:X}")
    w(f"DataType=0x{dtype:04X}")
    w(f"AccessType={access}")
    w(f"DefaultValue={default}")
    w(f"PDOMapping={pdo}")
    w("")


for index, name, otype, subs in objects:
    if otype == VAR:
        _, _, dtype, access, default, pdo = subs[0]
        entry(f"{index:04X}", name, dtype, access, default, pdo, VAR)
    else:
        w(f"[{index:04X}]")
        w(f"ParameterName={name}")
        w(f"ObjectType=0x{otype:X}")
        w(f"SubNumber={len(subs)}")
        w("")
        for sub, sname, dtype, access, default, pdo in subs:
            entry(f"{index:04X}sub{sub:X}", sname, dtype, access, default, pdo, VAR)

open("rl-fake-cia402.eds", "w").write("\n".join(out))
