//! STAGE 2 (scene builder): the graphics state and the Attribute/Transform block stack.

use std::rc::Rc;

use crate::error::{Error, Result, SourceLoc};
use crate::scene::props::{Props, TextureScope};
use crate::scene::transform::Transform;

use super::SceneBuilder;

/// The pbrt-v3 graphics state saved by AttributeBegin and restored by AttributeEnd.
#[derive(Clone, Debug, Default)]
pub(super) struct GraphicsState {
    /// Current material id (0 = the default matte).
    pub material: u32,
    /// The current area light, as captured parameters plus where it was declared.
    pub area_light: Option<(Props, SourceLoc)>,
    /// ReverseOrientation toggled an odd number of times.
    pub reverse_orientation: bool,
    /// Textures in scope (copy-on-write, as pbrt-v3 does after the book).
    pub textures: Rc<TextureScope>,
    /// Named materials in scope.
    pub named_materials: Rc<std::collections::HashMap<String, u32>>,
}

/// Which kind of block a stack frame belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Block {
    /// AttributeBegin … AttributeEnd (and ObjectBegin … ObjectEnd).
    Attribute,
    /// TransformBegin … TransformEnd.
    Transform,
    /// ObjectBegin … ObjectEnd.
    Object,
}

impl Block {
    pub(super) fn begin_keyword(self) -> &'static str {
        match self {
            Block::Attribute => "AttributeBegin",
            Block::Transform => "TransformBegin",
            Block::Object => "ObjectBegin",
        }
    }

    fn end_keyword(self) -> &'static str {
        match self {
            Block::Attribute => "AttributeEnd",
            Block::Transform => "TransformEnd",
            Block::Object => "ObjectEnd",
        }
    }
}

/// One saved state.
#[derive(Clone, Debug)]
pub(super) struct Frame {
    pub block: Block,
    pub loc: SourceLoc,
    ctm: [Transform; 2],
    active: [bool; 2],
    gs: Option<GraphicsState>,
}

impl SceneBuilder {
    /// Saves the transform (and, for attribute and object blocks, the graphics state).
    pub(super) fn push(&mut self, block: Block, loc: &SourceLoc) {
        let gs = (block != Block::Transform).then(|| self.gs.clone());
        self.stack.push(Frame { block, loc: loc.clone(), ctm: self.ctm, active: self.active, gs });
    }

    /// Restores what the matching begin saved; a mismatched or missing begin is an error.
    pub(super) fn pop(&mut self, block: Block, loc: &SourceLoc) -> Result<()> {
        let Some(top) = self.stack.last() else {
            return Err(Error::at(
                loc,
                format!("{} without a matching {}", block.end_keyword(), block.begin_keyword()),
            ));
        };
        if top.block != block {
            return Err(Error::at(
                loc,
                format!(
                    "{} closes the {} at {}; expected {}",
                    block.end_keyword(),
                    top.block.begin_keyword(),
                    top.loc,
                    top.block.end_keyword()
                ),
            ));
        }
        let Some(f) = self.stack.pop() else { return Ok(()) };
        self.ctm = f.ctm;
        self.active = f.active;
        if let Some(gs) = f.gs {
            self.gs = gs;
        }
        Ok(())
    }
}
