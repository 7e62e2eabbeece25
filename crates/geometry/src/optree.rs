//! Operator trees, shared by the object kinds built from trees (CSG trees, SDF models): n-ary
//! operators folded into balanced binary trees, and the validated form that evaluation walks,
//! a post-order list of nodes (the root last) built under a depth and a size limit.
//!
//! A tree has leaves (solids, distance primitives), binary operators (union, intersection,
//! difference, ...) and unary wrappers around a subtree (an SDF transform; CSG trees have
//! none). The object kind says what differs: the shape of its scene-format tree
//! ([`Source`]), and how each node is checked and stored and how a node's bound follows from
//! its operands' ([`Builder`]). This module does the walk, the limits and the node list,
//! once for both.

use crate::error::SceneError;

/// A binary operator of a tree as scene files give it, with n operands.
pub(crate) trait Operator: Copy + PartialEq {
    /// The union, which joins the operands that a difference subtracts.
    const UNION: Self;
    /// The difference (the first operand without the others).
    const DIFFERENCE: Self;
}

/// `operands` of `op` folded into a balanced binary tree by `node`, so that depth grows with
/// the logarithm of the count; a difference subtracts the balanced union of all operands
/// after the first. `what` names the operator in errors ("a CSG union").
///
/// # Errors
/// [`SceneError::Invalid`] when there are fewer than two operands.
pub(crate) fn fold<O: Operator, T>(
    what: &str,
    op: O,
    mut operands: Vec<T>,
    node: impl Fn(O, T, T) -> T,
) -> Result<T, SceneError> {
    if operands.len() < 2 {
        return Err(SceneError::Invalid(format!(
            "{what} needs at least two operands, found {}",
            operands.len()
        )));
    }
    if op == O::DIFFERENCE {
        let first = operands.remove(0);
        let rest = balanced(operands, &|a, b| node(O::UNION, a, b));
        return Ok(node(op, first, rest));
    }
    Ok(balanced(operands, &|a, b| node(op, a, b)))
}

/// `operands` (at least one) joined pairwise into a balanced binary tree.
fn balanced<T>(mut operands: Vec<T>, join: &impl Fn(T, T) -> T) -> T {
    if operands.len() == 1 {
        return operands.pop().expect("one operand");
    }
    let right = operands.split_off(operands.len() / 2);
    join(balanced(operands, join), balanced(right, join))
}

/// A node of a validated tree: operands are indices of earlier nodes.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Node<L, O, W> {
    /// A leaf.
    Leaf(L),
    /// A binary operator and its operands.
    Op(O, usize, usize),
    /// A wrapper and the subtree it wraps.
    Wrap(W, usize),
}

/// How a node of a scene's tree looks to [`OpTree::build`].
pub(crate) enum View<'a, S: Source> {
    /// A leaf's parameters ([`Builder::leaf`] checks them).
    Leaf(S::Leaf),
    /// A binary operator and its operands.
    Op(S::Op, &'a S, &'a S),
    /// A wrapper's parameters and the subtree it wraps.
    Wrap(&'a S::Transform, &'a S),
}

/// A scene's tree, as the object kind's scene-format type gives it.
pub(crate) trait Source: Sized {
    /// A leaf's parameters.
    type Leaf;
    /// The binary operator.
    type Op: Copy;
    /// A wrapper's parameters ([`std::convert::Infallible`]: the kind has no wrappers).
    type Transform;

    /// The node's shape.
    fn view(&self) -> View<'_, Self>;
}

/// What an object kind checks, stores and derives at each node while [`OpTree::build`]
/// validates a tree of `S`.
pub(crate) trait Builder<S: Source> {
    /// What a validated leaf stores.
    type Leaf;
    /// What a validated wrapper stores.
    type Wrap;
    /// What is derived for every subtree, from the leaves up (its box, ...).
    type Bound;

    /// Checks a leaf; returns what is stored and its bound.
    ///
    /// # Errors
    /// A parameter out of range.
    fn leaf(leaf: S::Leaf) -> Result<(Self::Leaf, Self::Bound), SceneError>;

    /// Checks an operator's parameters, before its operands.
    ///
    /// # Errors
    /// A parameter out of range.
    fn check_op(op: S::Op) -> Result<(), SceneError>;

    /// An operator's bound from its operands'.
    fn op_bound(op: S::Op, a: Self::Bound, b: Self::Bound) -> Self::Bound;

    /// Checks a wrapper's parameters, before its subtree; returns what is stored.
    ///
    /// # Errors
    /// A parameter out of range.
    fn wrap(t: &S::Transform) -> Result<Self::Wrap, SceneError>;

    /// A wrapper's bound from its subtree's.
    ///
    /// # Errors
    /// A bound out of range.
    fn wrap_bound(
        t: &S::Transform,
        w: &Self::Wrap,
        child: Self::Bound,
    ) -> Result<Self::Bound, SceneError>;
}

/// What the size limit of [`Limits`] counts.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Counted {
    /// Leaves, called by this name in errors ("solids").
    Leaves(&'static str),
    /// Every node.
    Nodes,
}

/// The limits a tree is built under.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    /// Names the tree in errors ("the CSG tree").
    pub what: &'static str,
    /// Most levels (the root is level 1).
    pub depth: usize,
    /// Most leaves or nodes.
    pub size: usize,
    /// What `size` counts.
    pub counted: Counted,
}

/// A validated tree: its nodes in post-order, the root last.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct OpTree<L, O, W> {
    nodes: Vec<Node<L, O, W>>,
}

impl<L, O: Copy, W> OpTree<L, O, W> {
    /// Validates the tree under `root` within `limits`, by the hooks of `B`; returns it, the
    /// root's bound and the number of leaves.
    ///
    /// # Errors
    /// [`SceneError::TooLarge`] for a tree deeper or larger than `limits`, and what the
    /// [`Builder`] hooks report.
    pub(crate) fn build<S, B>(
        root: &S,
        limits: &Limits,
    ) -> Result<(Self, B::Bound, u32), SceneError>
    where
        S: Source<Op = O>,
        B: Builder<S, Leaf = L, Wrap = W>,
    {
        let mut tree = Self { nodes: Vec::new() };
        let mut leaves = 0;
        let bound = tree.flatten::<S, B>(root, 1, limits, &mut leaves)?;
        Ok((tree, bound, leaves))
    }

    /// Appends `node`'s subtree (at level `depth`, after `leaves` leaves) in post-order;
    /// returns its bound.
    fn flatten<S, B>(
        &mut self,
        node: &S,
        depth: usize,
        limits: &Limits,
        leaves: &mut u32,
    ) -> Result<B::Bound, SceneError>
    where
        S: Source<Op = O>,
        B: Builder<S, Leaf = L, Wrap = W>,
    {
        if depth > limits.depth {
            return Err(SceneError::TooLarge(format!(
                "{} is deeper than {} levels",
                limits.what, limits.depth
            )));
        }
        let view = node.view();
        let size = match limits.counted {
            Counted::Nodes => Some((self.nodes.len(), "nodes")),
            Counted::Leaves(unit) => {
                matches!(view, View::Leaf(_)).then_some((*leaves as usize, unit))
            }
        };
        if let Some((n, unit)) = size
            && n >= limits.size
        {
            return Err(SceneError::TooLarge(format!(
                "{} has more than {} {unit}",
                limits.what, limits.size
            )));
        }
        match view {
            View::Leaf(source) => {
                let (leaf, bound) = B::leaf(source)?;
                *leaves += 1;
                self.nodes.push(Node::Leaf(leaf));
                Ok(bound)
            }
            View::Op(op, a, b) => {
                B::check_op(op)?;
                let ba = self.flatten::<S, B>(a, depth + 1, limits, leaves)?;
                let ia = self.root();
                let bb = self.flatten::<S, B>(b, depth + 1, limits, leaves)?;
                let ib = self.root();
                self.nodes.push(Node::Op(op, ia, ib));
                Ok(B::op_bound(op, ba, bb))
            }
            View::Wrap(t, child) => {
                let w = B::wrap(t)?;
                let bc = self.flatten::<S, B>(child, depth + 1, limits, leaves)?;
                let ic = self.root();
                let bound = B::wrap_bound(t, &w, bc)?;
                self.nodes.push(Node::Wrap(w, ic));
                Ok(bound)
            }
        }
    }

    /// The root's index (the last node).
    #[inline]
    #[must_use]
    pub(crate) fn root(&self) -> usize {
        self.nodes.len() - 1
    }

    /// Node `i`.
    #[inline]
    #[must_use]
    pub(crate) fn node(&self, i: usize) -> &Node<L, O, W> {
        &self.nodes[i]
    }

    /// Number of nodes.
    #[inline]
    #[must_use]
    pub(crate) fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes of the node list.
    #[must_use]
    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node<L, O, W>>()
    }
}
