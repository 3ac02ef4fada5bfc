//! The display list: commands in `heapless` storage with a capacity the user
//! picks. A full list is an [`Error::ListFull`], never a panic or an
//! allocation.

use crate::command::Command;
use crate::error::Error;

/// Up to `CAP` validated commands.
///
/// ```
/// use tilerast::prelude::*;
/// let mut list: DisplayList<2> = DisplayList::new();
/// list.push(Command::WidFill { rect: Rect::new(0, 0, 8, 8), wid: 1 })?;
/// assert_eq!(list.len(), 1);
/// // Commands outside the documented domain are refused at the door.
/// let bad = Vertex::new(Coord::from_num(-9000), Coord::ZERO, 0, Rgb::default());
/// assert_eq!(list.push(Command::Triangle { v: [bad; 3], state: State::default() }), Err(Error::CoordOutOfRange));
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct DisplayList<const CAP: usize> {
    cmds: heapless::Vec<Command, CAP>,
}

impl<const CAP: usize> DisplayList<CAP> {
    /// An empty list.
    pub const fn new() -> Self {
        DisplayList {
            cmds: heapless::Vec::new(),
        }
    }

    /// Validates and appends a command.
    pub fn push(&mut self, cmd: Command) -> Result<(), Error> {
        cmd.validate()?;
        self.cmds.push(cmd).map_err(|_| Error::ListFull)
    }

    /// Removes every command.
    pub fn clear(&mut self) {
        self.cmds.clear();
    }

    /// The capacity.
    pub const fn capacity(&self) -> usize {
        CAP
    }
}

impl<const CAP: usize> core::ops::Deref for DisplayList<CAP> {
    type Target = [Command];
    fn deref(&self) -> &[Command] {
        &self.cmds
    }
}
