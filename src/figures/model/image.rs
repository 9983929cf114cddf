//! Image grids: small multiples of equal-shape images (bases, patches).

use serde::{Deserialize, Serialize};

use super::heatmap::{ColorScale, check_limits};
use super::nan_serde::matrix_nan_as_null;
use crate::figures::FigureError;
use crate::session::Layout;

/// Small multiples: images of equal shape (basis images, patches) on one colour scale.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImageGrid {
    pub images: Vec<GridImage>,
    /// Images per row of the grid; 0 picks a near-square arrangement.
    #[serde(default)]
    pub columns: usize,
    pub colors: ColorScale,
}

/// One image; `values[0]` is the top row as drawn. A missing value is a cell without a
/// taxel, drawn as background.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridImage {
    #[serde(default)]
    pub caption: String,
    #[serde(with = "matrix_nan_as_null")]
    pub values: Vec<Vec<f64>>,
}

impl GridImage {
    /// Arrange one value per taxel as the sensor's image: the layout's row 0 (the sensor's
    /// base) is drawn at the bottom, cells without a taxel are missing.
    pub fn from_layout(
        caption: impl Into<String>,
        taxel_values: &[f64],
        layout: &Layout,
    ) -> Result<Self, FigureError> {
        let (rows, cols) = layout.grid_shape().ok_or_else(|| {
            FigureError::Invalid("a point layout has no grid to draw an image on".into())
        })?;
        if taxel_values.len() != layout.taxel_count() {
            return Err(FigureError::Invalid(format!(
                "{} values for a layout of {} taxels",
                taxel_values.len(),
                layout.taxel_count()
            )));
        }
        let mut values = vec![vec![f64::NAN; cols]; rows];
        for (i, &v) in taxel_values.iter().enumerate() {
            match layout.grid_cell(i) {
                Some((r, c)) if r < rows && c < cols => values[rows - 1 - r][c] = v,
                _ => {
                    return Err(FigureError::Invalid(format!(
                        "taxel {i} lies outside its {rows}×{cols} grid"
                    )));
                }
            }
        }
        Ok(GridImage {
            caption: caption.into(),
            values,
        })
    }
}

impl ImageGrid {
    /// Images of one shape with at least one cell.
    pub(super) fn validate(&self) -> Result<(), FigureError> {
        let g = self;
        let Some(first) = g.images.first() else {
            return Err(FigureError::Invalid(
                "an image grid needs at least one image".into(),
            ));
        };
        let shape = (first.values.len(), first.values.first().map_or(0, Vec::len));
        if shape.0 == 0 || shape.1 == 0 {
            return Err(FigureError::Invalid(
                "images need at least one row and one column".into(),
            ));
        }
        for (i, im) in g.images.iter().enumerate() {
            if im.values.len() != shape.0 || im.values.iter().any(|r| r.len() != shape.1) {
                return Err(FigureError::Invalid(format!(
                    "image {i} is not {}×{} like the first image",
                    shape.0, shape.1
                )));
            }
        }
        check_limits(&g.colors)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_from_sparse_layout_puts_base_at_bottom() {
        let layout = Layout::SparseGrid {
            rows: 2,
            cols: 3,
            cells: vec![[0, 0], [1, 2]],
        };
        let im = GridImage::from_layout("b1", &[1.0, 2.0], &layout).unwrap();
        assert_eq!(im.values[1][0], 1.0);
        assert_eq!(im.values[0][2], 2.0);
        assert!(im.values[0][0].is_nan());
        assert!(GridImage::from_layout("b", &[1.0], &layout).is_err());
    }
}
