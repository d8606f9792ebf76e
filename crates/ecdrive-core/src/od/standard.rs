//! The data types CiA 301 and CiA 402 give their objects: what a tool may assume for an object
//! of a device it has no dictionary of (a node served from an EDS file, a drive ecdrive has no
//! profile for). A device's own dictionary always wins.

use super::{DataType, ObjectAddress};

/// The standard type of `addr`, where CiA 301 (communication objects) or CiA 402 (drive
/// objects) fixes one.
pub fn data_type(addr: ObjectAddress) -> Option<DataType> {
    use DataType::{
        Integer8 as I8, Integer16 as I16, Integer32 as I32, Unsigned8 as U8, Unsigned16 as U16,
        Unsigned32 as U32, VisibleString as Str,
    };
    let (index, sub) = (addr.index, addr.sub);
    Some(match (index, sub) {
        // CiA 301.
        (0x1000, 0) | (0x1005..=0x1007, 0) | (0x1012, 0) | (0x1014, 0) => U32,
        (0x1001, 0) | (0x100D, 0) => U8,
        (0x1008..=0x100A, 0) => Str,
        (0x100C, 0) | (0x1015, 0) | (0x1017, 0) => U16,
        (0x1003 | 0x1010 | 0x1011 | 0x1016 | 0x1018, 0) => U8,
        (0x1003 | 0x1010 | 0x1011 | 0x1016 | 0x1018, _) => U32,
        (0x1200..=0x12FF, 0) => U8,
        (0x1200..=0x12FF, 1 | 2) => U32,
        (0x1200..=0x12FF, 3) => U8,
        (0x1400..=0x15FF | 0x1800..=0x19FF, 0) => U8,
        (0x1400..=0x15FF | 0x1800..=0x19FF, 1) => U32,
        (0x1400..=0x15FF | 0x1800..=0x19FF, 2 | 4) => U8,
        (0x1400..=0x15FF | 0x1800..=0x19FF, 3 | 5 | 6) => U16,
        (0x1600..=0x17FF | 0x1A00..=0x1BFF, 0) => U8,
        (0x1600..=0x17FF | 0x1A00..=0x1BFF, _) => U32,
        // CiA 402.
        (0x603F..=0x6041, 0) => U16,
        (0x605A..=0x605E, 0) => I16,
        (0x6060 | 0x6061 | 0x6098, 0) => I8,
        (0x6062..=0x6064 | 0x6069 | 0x606B | 0x606C | 0x607A | 0x607C | 0x60F4 | 0x60FC, 0) => I32,
        (0x60FF | 0x60B0 | 0x60B1, 0) => I32,
        (0x6065..=0x6068 | 0x606D..=0x606F, 0) => {
            if matches!(index, 0x6066 | 0x6068 | 0x606E | 0x606D | 0x606F) {
                U16
            } else {
                U32
            }
        }
        (0x6071..=0x6078 | 0x60B2, 0) => {
            if matches!(index, 0x6075 | 0x6076) {
                U32
            } else if index == 0x6072 || index == 0x6073 || index == 0x6074 {
                if index == 0x6072 { U16 } else { I16 }
            } else {
                I16
            }
        }
        (0x607B | 0x607D, 0) => U8,
        (0x607B | 0x607D, 1 | 2) => I32,
        (0x607E, 0) => U8,
        (0x607F..=0x6088, 0) => {
            if index == 0x6086 {
                I16
            } else {
                U32
            }
        }
        (0x608F | 0x6091 | 0x6092 | 0x6099, 0) => U8,
        (0x608F | 0x6091 | 0x6092 | 0x6099, 1 | 2) => U32,
        (0x609A | 0x60C5 | 0x60C6 | 0x6502, 0) => U32,
        (0x60B8 | 0x60B9, 0) => U16,
        (0x60BA..=0x60BD, 0) => I32,
        (0x60C0, 0) => I16,
        (0x60C1, 0) => U8,
        (0x60C1, 1) => I32,
        (0x60C2, 0) => U8,
        (0x60C2, 1) => U8,
        (0x60C2, 2) => I8,
        (0x60FD, 0) => U32,
        (0x60FE, 0) => U8,
        (0x60FE, 1 | 2) => U32,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_common_objects_have_their_types() {
        let t = |i, s| data_type(ObjectAddress::new(i, s));
        assert_eq!(t(0x1018, 1), Some(DataType::Unsigned32));
        assert_eq!(t(0x1017, 0), Some(DataType::Unsigned16));
        assert_eq!(t(0x1008, 0), Some(DataType::VisibleString));
        assert_eq!(t(0x6041, 0), Some(DataType::Unsigned16));
        assert_eq!(t(0x6060, 0), Some(DataType::Integer8));
        assert_eq!(t(0x6064, 0), Some(DataType::Integer32));
        assert_eq!(t(0x6081, 0), Some(DataType::Unsigned32));
        assert_eq!(t(0x6071, 0), Some(DataType::Integer16));
        assert_eq!(t(0x6072, 0), Some(DataType::Unsigned16));
        assert_eq!(t(0x60C2, 2), Some(DataType::Integer8));
        assert_eq!(t(0x2000, 0), None);
    }
}
