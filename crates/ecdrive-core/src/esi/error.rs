use core::fmt;
use std::path::PathBuf;

/// A place in an ESI file: 1-based line and column (columns count characters).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Position {
    /// Line, from 1.
    pub line: u32,
    /// Column, from 1, in characters.
    pub column: u32,
}

impl Position {
    /// A position.
    pub const fn new(line: u32, column: u32) -> Self {
        Self { line, column }
    }
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}, column {}", self.line, self.column)
    }
}

/// What kind of problem an [`EsiError`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EsiErrorKind {
    /// The file could not be read.
    Io,
    /// The bytes are not text in an encoding the parser understands.
    Encoding,
    /// The text is not well-formed XML.
    Xml,
    /// An element or attribute the ESI schema requires is missing.
    Missing,
    /// An element or attribute has a value that is not allowed (not a number, out of range,
    /// unknown keyword, …).
    Invalid,
}

/// Why an ESI file could not be read, with the line and column of the offending text.
///
/// Displayed as `line 42, column 7: <Entry> in <RxPdo> 0x1600 has BitLen "x": not a number`,
/// prefixed with the file name when the file was read with [`super::EsiFile::from_path`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EsiError {
    /// The kind of problem.
    pub kind: EsiErrorKind,
    /// Where it is (line 0 for I/O errors).
    pub position: Position,
    /// What is wrong, naming the element and attribute.
    pub message: String,
    /// The file, if it was read from one.
    pub path: Option<PathBuf>,
}

impl EsiError {
    /// An error at `position`.
    pub fn new(kind: EsiErrorKind, position: Position, message: impl Into<String>) -> Self {
        Self {
            kind,
            position,
            message: message.into(),
            path: None,
        }
    }

    /// The line (1-based; 0 when the error has no position).
    pub fn line(&self) -> u32 {
        self.position.line
    }

    /// The column (1-based; 0 when the error has no position).
    pub fn column(&self) -> u32 {
        self.position.column
    }

    /// The same error, naming the file it came from.
    pub fn with_path(mut self, path: impl Into<PathBuf>) -> Self {
        self.path = Some(path.into());
        self
    }
}

impl fmt::Display for EsiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = &self.path {
            write!(f, "{}: ", p.display())?;
        }
        if self.position.line == 0 {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.position, self.message)
        }
    }
}

impl std::error::Error for EsiError {}
