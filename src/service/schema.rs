//! Parts of the API description that the derives cannot say: the names a map of inputs may have,
//! the bounds of the items of an array, and the records of an event stream.

use utoipa::openapi::schema::{ArrayBuilder, ObjectBuilder, Schema, SchemaType, Type};
use utoipa::openapi::{Ref, RefOr};

/// The uncertain inputs' names (`damper_c1` … `damper_c10`, one per damper group).
pub const INPUT_NAME_PATTERN: &str = "^(youngs_modulus|mass_factor|damping_ratio|wind_speed|damper_c([1-9]|10))$";
/// Most inputs a study has: four, and one per damper group.
const MAX_INPUTS: usize = 14;

fn input_names() -> Schema {
    ObjectBuilder::new().schema_type(Type::String).pattern(Some(INPUT_NAME_PATTERN)).into()
}

/// `{"wind_speed": 40, ...}`: values held fixed, by input name.
pub fn fixed_inputs_schema() -> impl Into<RefOr<Schema>> {
    ObjectBuilder::new()
        .schema_type(Type::Object)
        .property_names(Some(input_names()))
        .max_properties(Some(MAX_INPUTS))
        .additional_properties(Some(ObjectBuilder::new().schema_type(Type::Number)))
}

/// `{"wind_speed": {"distribution": ...}, ...}`: marginals by input name.
pub fn marginals_schema() -> impl Into<RefOr<Schema>> {
    ObjectBuilder::new()
        .schema_type(Type::Object)
        .property_names(Some(input_names()))
        .max_properties(Some(MAX_INPUTS))
        .additional_properties(Some(Ref::from_schema_name("Marginal")))
}

/// The thresholds of an exceedance curve: 1 to 10 000 values of 0 to 10⁹ in the response's unit, or null.
pub fn thresholds_schema() -> impl Into<RefOr<Schema>> {
    let item =
        ObjectBuilder::new().schema_type(Type::Number).minimum(Some(0.0)).maximum(Some(crate::analysis::MAX_THRESHOLD));
    ArrayBuilder::new()
        .schema_type(SchemaType::from_iter([Type::Array, Type::Null]))
        .items(item)
        .min_items(Some(1))
        .max_items(Some(10_000))
}

/// One server-sent event of an operation's stream, as a client parses it: the record's `event`
/// field (always `operation`) and its `data`, an Operation as JSON text.
pub fn operation_event_schema() -> Schema {
    let data = ObjectBuilder::new()
        .schema_type(Type::String)
        .content_media_type("application/json")
        .content_schema(Some(Ref::from_schema_name("Operation")));
    ObjectBuilder::new()
        .schema_type(Type::Object)
        .description(Some("An `event: operation` record whose `data` is an Operation as JSON"))
        .property("event", ObjectBuilder::new().schema_type(Type::String).enum_values(Some(["operation"])))
        .property("data", data)
        .required("event")
        .required("data")
        .into()
}
