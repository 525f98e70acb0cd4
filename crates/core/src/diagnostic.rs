//! One type for a problem in a file: a [`Diagnostic`] (a stable [`Code`], a [`Severity`], a
//! location and a line for a person). The importers report their warnings as diagnostics
//! ([`crate::scene::Scene::warnings`]), `raycast check` reports its findings as diagnostics,
//! and an [`crate::Error`] carries the code of the diagnostic that stopped a load. Whoever acts
//! on a problem reads its code, never its message.
//!
//! Codes are the Khronos glTF-Validator's where the meaning is the same; their names
//! ([`Code::name`]) are stable and are what reports, the JSON of `raycast check` and the Python
//! package's exceptions (`.code`) show.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// How bad a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// The file cannot be read as written, or reads wrong.
    Error,
    /// Probably a mistake; reading goes on.
    Warning,
    /// Worth knowing.
    Info,
}

impl Severity {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Info => "info",
        }
    }
}

/// Declares [`Code`]: each variant with its stable name.
macro_rules! codes {
    ($($(#[$doc:meta])* $variant:ident = $name:literal,)*) => {
        /// A diagnostic's stable code. [`Code::name`] is its name in reports and JSON
        /// (`ACCESSOR_INDEX_OOB`); the variants are listed, and documented, by name in
        /// docs/check.md.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        #[allow(missing_docs)]
        pub enum Code {
            $($(#[$doc])* $variant,)*
        }

        impl Code {
            /// Every code, in the order of their names.
            pub const ALL: &[Code] = &[$(Code::$variant,)*];

            /// The stable name, e.g. `ACCESSOR_INDEX_OOB`.
            pub fn name(self) -> &'static str {
                match self {
                    $(Code::$variant => $name,)*
                }
            }
        }
    };
}

codes! {
    AccessorAnimationInputNegative = "ACCESSOR_ANIMATION_INPUT_NEGATIVE",
    AccessorAnimationInputNonIncreasing = "ACCESSOR_ANIMATION_INPUT_NON_INCREASING",
    AccessorAnimationSamplerOutputNonNormalizedQuaternion = "ACCESSOR_ANIMATION_SAMPLER_OUTPUT_NON_NORMALIZED_QUATERNION",
    AccessorElementOutOfMaxBound = "ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND",
    AccessorElementOutOfMinBound = "ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND",
    AccessorIndexOob = "ACCESSOR_INDEX_OOB",
    AccessorIndexPrimitiveRestart = "ACCESSOR_INDEX_PRIMITIVE_RESTART",
    AccessorInvalid = "ACCESSOR_INVALID",
    AccessorInvalidFloat = "ACCESSOR_INVALID_FLOAT",
    AccessorInvalidIbm = "ACCESSOR_INVALID_IBM",
    AccessorInvalidSign = "ACCESSOR_INVALID_SIGN",
    AccessorJointsIndexOob = "ACCESSOR_JOINTS_INDEX_OOB",
    AccessorMatrixAlignment = "ACCESSOR_MATRIX_ALIGNMENT",
    AccessorMaxMismatch = "ACCESSOR_MAX_MISMATCH",
    AccessorMinMaxCount = "ACCESSOR_MIN_MAX_COUNT",
    AccessorMinMismatch = "ACCESSOR_MIN_MISMATCH",
    AccessorNonClamped = "ACCESSOR_NON_CLAMPED",
    AccessorNormalizedInvalid = "ACCESSOR_NORMALIZED_INVALID",
    AccessorOffsetAlignment = "ACCESSOR_OFFSET_ALIGNMENT",
    AccessorSmallBytestride = "ACCESSOR_SMALL_BYTESTRIDE",
    AccessorSparseCountOutOfRange = "ACCESSOR_SPARSE_COUNT_OUT_OF_RANGE",
    AccessorSparseIndexOob = "ACCESSOR_SPARSE_INDEX_OOB",
    AccessorSparseIndicesNonIncreasing = "ACCESSOR_SPARSE_INDICES_NON_INCREASING",
    AccessorSparseInvalid = "ACCESSOR_SPARSE_INVALID",
    AccessorTooLong = "ACCESSOR_TOO_LONG",
    AccessorTotalOffsetAlignment = "ACCESSOR_TOTAL_OFFSET_ALIGNMENT",
    AccessorVector3NonUnit = "ACCESSOR_VECTOR3_NON_UNIT",
    AccessorWeightsNegative = "ACCESSOR_WEIGHTS_NEGATIVE",
    AccessorWeightsNonNormalized = "ACCESSOR_WEIGHTS_NON_NORMALIZED",
    AnimationChannelTargetNodeMatrix = "ANIMATION_CHANNEL_TARGET_NODE_MATRIX",
    AnimationChannelTargetNodeWeightsNoMorphs = "ANIMATION_CHANNEL_TARGET_NODE_WEIGHTS_NO_MORPHS",
    AnimationDuplicateTargets = "ANIMATION_DUPLICATE_TARGETS",
    AnimationSamplerAccessorWithBytestride = "ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE",
    AnimationSamplerInputAccessorInvalidFormat = "ANIMATION_SAMPLER_INPUT_ACCESSOR_INVALID_FORMAT",
    AnimationSamplerInputAccessorTooFewElements = "ANIMATION_SAMPLER_INPUT_ACCESSOR_TOO_FEW_ELEMENTS",
    AnimationSamplerInputAccessorWithoutBounds = "ANIMATION_SAMPLER_INPUT_ACCESSOR_WITHOUT_BOUNDS",
    AnimationSamplerInvalid = "ANIMATION_SAMPLER_INVALID",
    AnimationSamplerOutputAccessorInvalidCount = "ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_COUNT",
    AnimationSamplerOutputAccessorInvalidFormat = "ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_FORMAT",
    ArrayLengthNotInList = "ARRAY_LENGTH_NOT_IN_LIST",
    ArrayTypeMismatch = "ARRAY_TYPE_MISMATCH",
    AssetMinVersionGreaterThanVersion = "ASSET_MIN_VERSION_GREATER_THAN_VERSION",
    AssetTooLarge = "ASSET_TOO_LARGE",
    BufferByteLengthMismatch = "BUFFER_BYTE_LENGTH_MISMATCH",
    BufferDataUriMimeTypeInvalid = "BUFFER_DATA_URI_MIME_TYPE_INVALID",
    BufferGlbChunkTooBig = "BUFFER_GLB_CHUNK_TOO_BIG",
    BufferMissingGlbData = "BUFFER_MISSING_GLB_DATA",
    BufferNoData = "BUFFER_NO_DATA",
    BufferViewInvalidByteStride = "BUFFER_VIEW_INVALID_BYTE_STRIDE",
    BufferViewTargetOverride = "BUFFER_VIEW_TARGET_OVERRIDE",
    BufferViewTooBigByteStride = "BUFFER_VIEW_TOO_BIG_BYTE_STRIDE",
    BufferViewTooLong = "BUFFER_VIEW_TOO_LONG",
    CameraInvalid = "CAMERA_INVALID",
    CameraXmagYmagNegative = "CAMERA_XMAG_YMAG_NEGATIVE",
    CameraXmagYmagZero = "CAMERA_XMAG_YMAG_ZERO",
    CameraYfovGequalPi = "CAMERA_YFOV_GEQUAL_PI",
    CameraZfarLequalZnear = "CAMERA_ZFAR_LEQUAL_ZNEAR",
    DataUriGlb = "DATA_URI_GLB",
    DegenerateFace = "DEGENERATE_FACE",
    DegenerateTriangles = "DEGENERATE_TRIANGLES",
    DracoInvalid = "DRACO_INVALID",
    DuplicateElements = "DUPLICATE_ELEMENTS",
    EmptyEntity = "EMPTY_ENTITY",
    EmptyScene = "EMPTY_SCENE",
    Failed = "FAILED",
    FileTooLarge = "FILE_TOO_LARGE",
    FileTypeMismatch = "FILE_TYPE_MISMATCH",
    GlbChunkLengthUnaligned = "GLB_CHUNK_LENGTH_UNALIGNED",
    GlbChunkTooBig = "GLB_CHUNK_TOO_BIG",
    GlbDuplicateChunk = "GLB_DUPLICATE_CHUNK",
    GlbEmptyChunk = "GLB_EMPTY_CHUNK",
    GlbExtraData = "GLB_EXTRA_DATA",
    GlbInvalidMagic = "GLB_INVALID_MAGIC",
    GlbInvalidVersion = "GLB_INVALID_VERSION",
    GlbLengthMismatch = "GLB_LENGTH_MISMATCH",
    GlbLengthTooSmall = "GLB_LENGTH_TOO_SMALL",
    GlbUnexpectedBinChunk = "GLB_UNEXPECTED_BIN_CHUNK",
    GlbUnexpectedEndOfChunkData = "GLB_UNEXPECTED_END_OF_CHUNK_DATA",
    GlbUnexpectedEndOfChunkHeader = "GLB_UNEXPECTED_END_OF_CHUNK_HEADER",
    GlbUnexpectedEndOfHeader = "GLB_UNEXPECTED_END_OF_HEADER",
    GlbUnexpectedFirstChunk = "GLB_UNEXPECTED_FIRST_CHUNK",
    GlbUnknownChunkType = "GLB_UNKNOWN_CHUNK_TYPE",
    GoldenMismatch = "GOLDEN_MISMATCH",
    GoldenMissing = "GOLDEN_MISSING",
    GoldenUpdated = "GOLDEN_UPDATED",
    ImageBufferViewWithBytestride = "IMAGE_BUFFER_VIEW_WITH_BYTESTRIDE",
    ImageDataInvalid = "IMAGE_DATA_INVALID",
    ImageMimeTypeInvalid = "IMAGE_MIME_TYPE_INVALID",
    ImageUnexpectedEos = "IMAGE_UNEXPECTED_EOS",
    ImageUnrecognizedFormat = "IMAGE_UNRECOGNIZED_FORMAT",
    ImporterNote = "IMPORTER_NOTE",
    IndexOob = "INDEX_OOB",
    InstancingInvalid = "INSTANCING_INVALID",
    InternalPanic = "INTERNAL_PANIC",
    InvalidExtensionNameFormat = "INVALID_EXTENSION_NAME_FORMAT",
    InvalidIbmAccessorCount = "INVALID_IBM_ACCESSOR_COUNT",
    InvalidIndex = "INVALID_INDEX",
    InvalidJson = "INVALID_JSON",
    InvalidUri = "INVALID_URI",
    InvertedNormals = "INVERTED_NORMALS",
    IoError = "IO_ERROR",
    LoadFailed = "LOAD_FAILED",
    MeshoptInvalid = "MESHOPT_INVALID",
    MeshHoles = "MESH_HOLES",
    MeshInconsistentWinding = "MESH_INCONSISTENT_WINDING",
    MeshInvalidWeightsCount = "MESH_INVALID_WEIGHTS_COUNT",
    MeshNonManifold = "MESH_NON_MANIFOLD",
    MeshPrimitivesUnequalTargetsCount = "MESH_PRIMITIVES_UNEQUAL_TARGETS_COUNT",
    MeshPrimitiveAccessorUnaligned = "MESH_PRIMITIVE_ACCESSOR_UNALIGNED",
    MeshPrimitiveAccessorWithoutBytestride = "MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE",
    MeshPrimitiveAttributesAccessorInvalidFormat = "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT",
    MeshPrimitiveAttributesAccessorUnsignedInt = "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_UNSIGNED_INT",
    MeshPrimitiveGeneratedTangentSpace = "MESH_PRIMITIVE_GENERATED_TANGENT_SPACE",
    MeshPrimitiveIncompatibleMode = "MESH_PRIMITIVE_INCOMPATIBLE_MODE",
    MeshPrimitiveIndexedSemanticContinuity = "MESH_PRIMITIVE_INDEXED_SEMANTIC_CONTINUITY",
    MeshPrimitiveIndicesAccessorInvalidFormat = "MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT",
    MeshPrimitiveIndicesAccessorWithBytestride = "MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE",
    MeshPrimitiveInvalidAttribute = "MESH_PRIMITIVE_INVALID_ATTRIBUTE",
    MeshPrimitiveJointsInvalid = "MESH_PRIMITIVE_JOINTS_INVALID",
    MeshPrimitiveJointsWeightsMismatch = "MESH_PRIMITIVE_JOINTS_WEIGHTS_MISMATCH",
    MeshPrimitiveMorphTargetInvalidAttributeCount = "MESH_PRIMITIVE_MORPH_TARGET_INVALID_ATTRIBUTE_COUNT",
    MeshPrimitiveMorphTargetNoBaseAccessor = "MESH_PRIMITIVE_MORPH_TARGET_NO_BASE_ACCESSOR",
    MeshPrimitiveNoPosition = "MESH_PRIMITIVE_NO_POSITION",
    MeshPrimitiveNoTangentSpace = "MESH_PRIMITIVE_NO_TANGENT_SPACE",
    MeshPrimitivePositionAccessorWithoutBounds = "MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS",
    MeshPrimitiveTangentWithoutNormal = "MESH_PRIMITIVE_TANGENT_WITHOUT_NORMAL",
    MeshPrimitiveTooFewTexcoords = "MESH_PRIMITIVE_TOO_FEW_TEXCOORDS",
    MeshPrimitiveUnequalAccessorCount = "MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT",
    MissingReference = "MISSING_REFERENCE",
    NodeHierarchyTooDeep = "NODE_HIERARCHY_TOO_DEEP",
    NodeLoop = "NODE_LOOP",
    NodeMatrixNonTrs = "NODE_MATRIX_NON_TRS",
    NodeMatrixTrs = "NODE_MATRIX_TRS",
    NodeParentOverride = "NODE_PARENT_OVERRIDE",
    NodeSkinnedMeshWithoutSkin = "NODE_SKINNED_MESH_WITHOUT_SKIN",
    NodeSkinNoScene = "NODE_SKIN_NO_SCENE",
    NodeSkinWithNonSkinnedMesh = "NODE_SKIN_WITH_NON_SKINNED_MESH",
    NodeTransformNotFinite = "NODE_TRANSFORM_NOT_FINITE",
    NodeTransformNotInvertible = "NODE_TRANSFORM_NOT_INVERTIBLE",
    NodeWeightsInvalid = "NODE_WEIGHTS_INVALID",
    NonFinitePosition = "NON_FINITE_POSITION",
    NonRelativeUri = "NON_RELATIVE_URI",
    NotFound = "NOT_FOUND",
    ObjNotText = "OBJ_NOT_TEXT",
    ObjNoData = "OBJ_NO_DATA",
    ObjNoStatement = "OBJ_NO_STATEMENT",
    ObjParseError = "OBJ_PARSE_ERROR",
    OneOfMismatch = "ONE_OF_MISMATCH",
    PathOutsideAsset = "PATH_OUTSIDE_ASSET",
    PatternMismatch = "PATTERN_MISMATCH",
    PlyHeaderError = "PLY_HEADER_ERROR",
    PlyParseError = "PLY_PARSE_ERROR",
    PlyTruncated = "PLY_TRUNCATED",
    QuadricInvalid = "QUADRIC_INVALID",
    RotationNonUnit = "ROTATION_NON_UNIT",
    SceneNonRootNode = "SCENE_NON_ROOT_NODE",
    SceneSizeOutOfRange = "SCENE_SIZE_OUT_OF_RANGE",
    SkinIbmAccessorWithBytestride = "SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE",
    SkinIbmInvalidFormat = "SKIN_IBM_INVALID_FORMAT",
    SkinNoCommonRoot = "SKIN_NO_COMMON_ROOT",
    SkinSkeletonInvalid = "SKIN_SKELETON_INVALID",
    StlNotStl = "STL_NOT_STL",
    StlParseError = "STL_PARSE_ERROR",
    StlTruncated = "STL_TRUNCATED",
    Truncated = "TRUNCATED",
    TypeMismatch = "TYPE_MISMATCH",
    UndeclaredExtension = "UNDECLARED_EXTENSION",
    UndefinedProperty = "UNDEFINED_PROPERTY",
    UnknownAssetMajorVersion = "UNKNOWN_ASSET_MAJOR_VERSION",
    UnknownAssetMinorVersion = "UNKNOWN_ASSET_MINOR_VERSION",
    UnresolvedReference = "UNRESOLVED_REFERENCE",
    UnsatisfiedDependency = "UNSATISFIED_DEPENDENCY",
    UnsupportedExtension = "UNSUPPORTED_EXTENSION",
    UnsupportedFileType = "UNSUPPORTED_FILE_TYPE",
    UnusedExtensionRequired = "UNUSED_EXTENSION_REQUIRED",
    Usage = "USAGE",
    UsdzInvalidPackage = "USDZ_INVALID_PACKAGE",
    UsdCompositionCycle = "USD_COMPOSITION_CYCLE",
    UsdCompositionError = "USD_COMPOSITION_ERROR",
    UsdInvalidPath = "USD_INVALID_PATH",
    UsdReaderCrashed = "USD_READER_CRASHED",
    UsdUnknownValueType = "USD_UNKNOWN_VALUE_TYPE",
    UsdUnreadableValue = "USD_UNREADABLE_VALUE",
    UsdUnsupportedLayer = "USD_UNSUPPORTED_LAYER",
    ValueMultipleOf = "VALUE_MULTIPLE_OF",
    ValueNotInList = "VALUE_NOT_IN_LIST",
    ValueNotInRange = "VALUE_NOT_IN_RANGE",
}

impl Code {
    /// The code named `name`, if there is one.
    pub fn from_name(name: &str) -> Option<Code> {
        Code::ALL.iter().copied().find(|code| code.name() == name)
    }
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl Serialize for Code {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for Code {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Code, D::Error> {
        let name = String::deserialize(deserializer)?;
        Code::from_name(&name)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown code '{name}'")))
    }
}

/// One problem found in a file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Diagnostic {
    /// Stable code.
    pub code: Code,
    /// Error, warning or info.
    pub severity: Severity,
    /// Where: a JSON pointer (glTF), a prim path (USD), `line N` (OBJ), or empty for the whole
    /// file.
    pub location: String,
    /// One line for a person.
    pub message: String,
    /// Where the reader came to the problem from, when that is not where it lies (an accessor
    /// read for a mesh primitive, a node): shown after the message as `(read for ...)`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reached_from: Option<String>,
    /// What the line is headed with instead of the location, for a problem whose line names
    /// its kind first (a USD composition problem: `composition: ...`, its location the prim
    /// the arc is authored on). Not part of a report's JSON.
    #[serde(skip)]
    pub heading: Option<&'static str>,
}

impl Diagnostic {
    /// A diagnostic of `severity`.
    pub fn new(
        code: Code,
        severity: Severity,
        location: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Diagnostic {
            code,
            severity,
            location: location.into(),
            message: message.into(),
            reached_from: None,
            heading: None,
        }
    }

    /// The message, followed by `(read for ...)` when it was reached from elsewhere: the
    /// diagnostic without its location.
    pub fn text(&self) -> String {
        match &self.reached_from {
            Some(at) => format!("{} (read for {at})", self.message),
            None => self.message.clone(),
        }
    }

    /// The same diagnostic reached from `at` (a primitive, a node), so that a fail-fast error
    /// names both; a diagnostic that lies under `at`, or was reached from somewhere already,
    /// is kept as it is.
    pub fn within(mut self, at: &str) -> Diagnostic {
        if !self.location.starts_with(at) && self.reached_from.is_none() {
            self.reached_from = Some(at.to_string());
        }
        self
    }

    /// An error diagnostic.
    pub fn error(code: Code, location: impl Into<String>, message: impl Into<String>) -> Self {
        Diagnostic::new(code, Severity::Error, location, message)
    }

    /// A warning diagnostic.
    pub fn warning(code: Code, location: impl Into<String>, message: impl Into<String>) -> Self {
        Diagnostic::new(code, Severity::Warning, location, message)
    }

    /// An importer's warning about the whole file, of code `code`.
    pub fn note(code: Code, message: impl Into<String>) -> Self {
        Diagnostic::warning(code, "", message)
    }
}

impl fmt::Display for Diagnostic {
    /// `location: message` (`heading: message` with a heading), or the message alone for the
    /// whole file; then `(read for ...)` when it was reached from elsewhere.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.heading {
            Some(heading) => write!(f, "{heading}: ")?,
            None if !self.location.is_empty() => write!(f, "{}: ", self.location)?,
            None => {}
        }
        f.write_str(&self.text())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names are unique, upper-case words joined by `_`, listed in order, and read back.
    #[test]
    fn names_are_unique_sorted_and_read_back() {
        let names: Vec<&str> = Code::ALL.iter().map(|c| c.name()).collect();
        assert!(names.windows(2).all(|w| w[0] < w[1]), "{names:?}");
        for &code in Code::ALL {
            let name = code.name();
            assert!(name
                .bytes()
                .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_'));
            assert_eq!(Code::from_name(name), Some(code));
            let json = serde_json::to_string(&code).expect("serialise");
            assert_eq!(json, format!("\"{name}\""));
            assert_eq!(
                serde_json::from_str::<Code>(&json).expect("read back"),
                code
            );
        }
        assert_eq!(Code::from_name("NO_SUCH_CODE"), None);
        assert!(serde_json::from_str::<Code>("\"NO_SUCH_CODE\"").is_err());
    }

    /// A diagnostic shows as `location: message`, or the message alone.
    #[test]
    fn display_joins_location_and_message() {
        let at = Diagnostic::error(Code::AccessorTooLong, "/accessors/0", "too long");
        assert_eq!(at.to_string(), "/accessors/0: too long");
        assert_eq!(
            Diagnostic::note(Code::ImporterNote, "whole").to_string(),
            "whole"
        );
        let reached = at.within("/meshes/0/primitives/0").within("/nodes/3");
        assert_eq!(reached.text(), "too long (read for /meshes/0/primitives/0)");
        assert_eq!(
            reached.to_string(),
            "/accessors/0: too long (read for /meshes/0/primitives/0)"
        );
        let headed = Diagnostic {
            heading: Some("composition"),
            ..Diagnostic::warning(Code::MissingReference, "/World", "unresolved layer")
        };
        assert_eq!(headed.to_string(), "composition: unresolved layer");
        let under = Diagnostic::error(Code::AccessorTooLong, "/nodes/3/mesh", "bad");
        assert_eq!(under.within("/nodes/3").to_string(), "/nodes/3/mesh: bad");
    }
}
