//! The preview page of a run: what a technical artist opens to judge a LOD chain without an
//! engine. For `frond lod` (`<name>_preview.html` beside the files): a live three.js view of the
//! combined file with a LOD slider, the cost table read back from the written files, and per LOD
//! its still at its own screen height beside LOD0's from the same camera, their difference
//! image, the wind loop as a flip-book, its atlas, the method and why, and the error measured at
//! its own size. `frond batch` adds an index page, `frond sweep` a page of its charts
//! ([`index_page`], [`html`]).
//!
//! Every picture is frond's own render (`frond-render`), so the page works with nothing
//! installed beyond a browser; the live view needs the folder served over HTTP or the file
//! picked by hand (see [`viewer`]).

pub mod charts;
pub mod error;
pub mod html;
pub mod index_page;
pub mod lod_page;
pub mod stills;
pub mod units;
pub mod viewer;

pub use error::PreviewError;
pub use lod_page::{
    Lod0Pictures, Lod0Request, LodPreviewPictures, LodPreviewRequest, PreviewFiles, lod_page,
    lod_pictures, lod_pictures_after, lod0_pictures, preview_name,
};
pub use viewer::{VIEWER_DIR, viewer_files};
