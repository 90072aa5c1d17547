//! What the shader and its CPU mirror share, the ground floor: the Pod contract with the
//! shader ([`layout`]) and the numeric kernel ([`real`]). Nothing here imports from the rest
//! of glint; everything else may import it.

pub mod layout;
pub mod real;
