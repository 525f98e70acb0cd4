//! What the USD text reader read past without failing its layer (openusd's
//! `sdf::ReadWarning`), as warnings: attributes whose type name Sdf's value type registry does
//! not know (a typo such as `flaot`) keep their specs, and their values are not read, as
//! usd-core leaves them unread (`Sdf.UnregisteredValue`). One warning for all of them.

use openusd::sdf::ReadWarning;
use openusd::usd::Stage;
use raycast_core::diagnostic::{Code, Diagnostic};

/// The words of the one warning for attributes of unknown value types (`raycast check` maps
/// it to `USD_UNKNOWN_VALUE_TYPE`).
pub const UNKNOWN_VALUE_TYPE: &str = "of value types USD does not know";

/// How many attributes of unknown types the warning names before counting the rest.
const SHOWN: usize = 3;

/// The read warnings of every layer of `stage`, each one line: one for all the attributes of
/// unknown value types (sorted by path), one per other warning.
pub fn warnings(stage: &Stage) -> Vec<Diagnostic> {
    let mut unknown = Vec::new();
    let mut lines = Vec::new();
    for identifier in stage.layer_identifiers() {
        let Some(layer) = stage.layer(&identifier) else {
            continue;
        };
        for warning in layer.data().read_warnings() {
            match warning {
                ReadWarning::UnknownValueType { path, type_name } => {
                    unknown.push(format!("{path} ({type_name})"))
                }
                other => lines.push(Diagnostic::warning(
                    Code::ImporterNote,
                    identifier.clone(),
                    other.to_string(),
                )),
            }
        }
    }
    unknown.sort();
    unknown.dedup();
    let note = unknown_note(&unknown);
    lines.extend(note.map(|line| Diagnostic::note(Code::UsdUnknownValueType, line)));
    lines
}

/// One line for the attributes of unknown value types, naming the first few.
fn unknown_note(unknown: &[String]) -> Option<String> {
    if unknown.is_empty() {
        return None;
    }
    let shown = unknown[..unknown.len().min(SHOWN)].join(", ");
    let more = match unknown.len().saturating_sub(SHOWN) {
        0 => String::new(),
        rest => format!(" and {rest} more"),
    };
    let attributes = if unknown.len() == 1 {
        "attribute"
    } else {
        "attributes"
    };
    Some(format!(
        "{} {attributes} {UNKNOWN_VALUE_TYPE}, values not read (as usd-core leaves them): \
         {shown}{more}",
        unknown.len()
    ))
}
