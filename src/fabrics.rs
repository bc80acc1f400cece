//! The fabric library (B3): measured fabrics and the mapping from textile measurements to
//! element constants. Bending rigidity maps to hinges and tensile and shear stiffness to
//! membrane constants, all per unit area or width, so a fabric behaves the same at any
//! particle spacing.

use serde::{Deserialize, Serialize};

use crate::components::{BendingDesc, BendingLawDesc, ClothMaterial, MembraneDesc};

/// Standard gravity used for bending lengths [m/s²] (the value Bricis uses, eq. 6.56).
pub const STANDARD_GRAVITY: f32 = 9.80665;

/// Tensile stiffness [N/m] used when a fabric has no tensile measurement: a firm woven
/// fabric, stiff enough that weight alone stretches a drape by well under 1 %.
pub const DEFAULT_TENSILE: f32 = 2000.0;
/// Shear stiffness [N/m] used when a fabric has no shear measurement: about 1 gf/cm/° on
/// the Kawabata shear tester, typical of plain cotton and polyester weaves.
pub const DEFAULT_SHEAR: f32 = 50.0;
/// Poisson ratio used when none is given: Bricis's value for every cloth (§6.3.3.1).
pub const DEFAULT_POISSON: f32 = 0.25;

/// A fabric from the library, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FabricName {
    /// 100 % polyester (Bricis tables 6.1–6.3).
    Polyester,
    /// 100 % cotton.
    Cotton,
    /// 100 % wool.
    Wool,
    /// 50 % polyester, 50 % cotton.
    Polycotton,
}

impl FabricName {
    /// All library fabrics.
    pub const ALL: [FabricName; 4] =
        [FabricName::Polyester, FabricName::Cotton, FabricName::Wool, FabricName::Polycotton];

    /// Bricis's measurements (UMIST; digest §2.10): thickness [m], bending rigidity warp
    /// and weft [N·m²/m], areal density [kg/m²]. No tensile or shear data were measured.
    #[expect(clippy::excessive_precision, reason = "the digits the thesis publishes")]
    pub fn measurements(self) -> FabricMeasurements {
        let (thickness, warp, weft, density) = match self {
            FabricName::Polyester => (2.58e-4, 3.893240e-6, 2.755669e-6, 0.1182),
            FabricName::Cotton => (7.81e-4, 1.998595e-5, 1.587697e-5, 0.2578),
            FabricName::Wool => (6.41e-4, 1.319975e-5, 9.286898e-6, 0.2138),
            FabricName::Polycotton => (4.46e-4, 1.010085e-5, 5.060231e-6, 0.1164),
        };
        FabricMeasurements {
            areal_density: density,
            thickness,
            bending: BendingMeasurement::Rigidity { warp, weft },
            tensile_warp: None,
            tensile_weft: None,
            shear: None,
            poisson: None,
        }
    }
}

/// Bending, as a rigidity or as the bending length of a cantilever test.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum BendingMeasurement {
    /// Flexural rigidity per unit width, warp and weft [N·m²/m].
    Rigidity {
        /// Warp rigidity.
        warp: f32,
        /// Weft rigidity.
        weft: f32,
    },
    /// Bending length `c` of a cantilever test (ASTM D1388), warp and weft [m]:
    /// `B = ρ g c³`.
    BendingLength {
        /// Warp bending length.
        warp: f32,
        /// Weft bending length.
        weft: f32,
    },
}

/// What a textile laboratory measures of a fabric. Missing tensile, shear and Poisson
/// values fall back to [`DEFAULT_TENSILE`], [`DEFAULT_SHEAR`] and [`DEFAULT_POISSON`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FabricMeasurements {
    /// Mass per area [kg/m²].
    pub areal_density: f32,
    /// Thickness [m]; used for contact thickness.
    pub thickness: f32,
    /// Bending rigidity or bending length.
    pub bending: BendingMeasurement,
    /// Tensile stiffness along the warp [N/m] (force per width per unit strain).
    #[serde(default)]
    pub tensile_warp: Option<f32>,
    /// Tensile stiffness along the weft [N/m].
    #[serde(default)]
    pub tensile_weft: Option<f32>,
    /// In-plane shear stiffness [N/m] (per radian of shear angle).
    #[serde(default)]
    pub shear: Option<f32>,
    /// Poisson ratio [-].
    #[serde(default)]
    pub poisson: Option<f32>,
}

impl FabricMeasurements {
    /// Bending rigidity warp and weft [N·m].
    pub fn rigidity(&self) -> (f32, f32) {
        match self.bending {
            BendingMeasurement::Rigidity { warp, weft } => (warp, weft),
            BendingMeasurement::BendingLength { warp, weft } => {
                let w = self.areal_density * STANDARD_GRAVITY;
                (w * warp.powi(3), w * weft.powi(3))
            }
        }
    }

    /// Bending length `c = (B / (ρ g))^(1/3)` warp and weft [m].
    pub fn bending_length(&self) -> (f32, f32) {
        let (warp, weft) = self.rigidity();
        let w = self.areal_density * STANDARD_GRAVITY;
        ((warp / w).cbrt(), (weft / w).cbrt())
    }

    /// The element constants: an anisotropic membrane (`d₁`, `d₂` the tensile stiffnesses,
    /// `d₃ = ν √(d₁ d₂)`, `d₄` the shear stiffness) and linear bending hinges.
    pub fn material(&self) -> ClothMaterial {
        let d1 = self.tensile_warp.unwrap_or(DEFAULT_TENSILE);
        let d2 = self.tensile_weft.unwrap_or(d1);
        let nu = self.poisson.unwrap_or(DEFAULT_POISSON);
        let (warp, weft) = self.rigidity();
        ClothMaterial {
            density: self.areal_density,
            stretch: None,
            shear: None,
            bend: None,
            membrane: Some(MembraneDesc::Anisotropic {
                d1,
                d2,
                d3: nu * (d1 * d2).sqrt(),
                d4: self.shear.unwrap_or(DEFAULT_SHEAR),
            }),
            bending: Some(BendingDesc { warp, weft, twist: None, law: BendingLawDesc::Linear }),
        }
    }
}

/// A fabric in a scene: from the library by name, or from measurements.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum FabricDesc {
    /// A library fabric.
    Named(FabricName),
    /// Measured values.
    Measured(FabricMeasurements),
}

impl FabricDesc {
    /// The measurements behind this fabric.
    pub fn measurements(&self) -> FabricMeasurements {
        match self {
            FabricDesc::Named(name) => name.measurements(),
            FabricDesc::Measured(m) => *m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_bending_lengths_match_the_digest() {
        // Digest §2.10 derived table: c warp / weft [cm].
        let expected = [
            (FabricName::Polyester, 1.50, 1.33),
            (FabricName::Cotton, 1.99, 1.84),
            (FabricName::Wool, 1.85, 1.64),
            (FabricName::Polycotton, 2.07, 1.64),
        ];
        for (fabric, warp, weft) in expected {
            let (c_warp, c_weft) = fabric.measurements().bending_length();
            assert!((100.0 * c_warp - warp).abs() < 0.01, "{fabric:?} warp {c_warp}");
            assert!((100.0 * c_weft - weft).abs() < 0.01, "{fabric:?} weft {c_weft}");
        }
    }

    #[test]
    fn a_bending_length_gives_back_its_rigidity() {
        let cotton = FabricName::Cotton.measurements();
        let (c_warp, c_weft) = cotton.bending_length();
        let measured =
            FabricMeasurements { bending: BendingMeasurement::BendingLength { warp: c_warp, weft: c_weft }, ..cotton };
        let (warp, weft) = measured.rigidity();
        assert!((warp / 1.998595e-5 - 1.0).abs() < 1e-4 && (weft / 1.587697e-5 - 1.0).abs() < 1e-4);
    }
}
