//! What the shader and its CPU mirror share, the ground floor: the Pod contract with the
//! shader ([`layout`]), the numeric kernel ([`real`]) and the 8-bit encodings of a linear
//! image ([`encoding`]), which the scene names and the image writer applies. Nothing here imports from the rest
//! of glint; everything else may import it.

pub mod encoding;
pub mod layout;
pub mod real;
