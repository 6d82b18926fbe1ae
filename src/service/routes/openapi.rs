//! The API description, generated from the routes themselves (utoipa-axum registers a handler and
//! its documentation together, so paths and methods cannot drift). Responses that come from the
//! shared machinery rather than from a handler are added here by the same rules the machinery
//! follows, so each operation documents exactly the statuses it can return.

use crate::service::ServeArgs;
use utoipa::OpenApi;
use utoipa::openapi::path::{Operation, ParameterIn};
use utoipa::openapi::schema::{ObjectBuilder, Schema, Type};
use utoipa::openapi::security::{Http, HttpAuthScheme, SecurityRequirement, SecurityScheme};
use utoipa::openapi::{ContentBuilder, Ref, RefOr, Response, ResponseBuilder};

#[derive(OpenApi)]
#[openapi(
    info(
        title = "windmeta",
        description = "Rapid uncertainty quantification of tall buildings under stochastic wind: PC-NARX \
            metamodels calibrated on a Latin hypercube of reference storms, sampled for peak-response \
            exceedance curves, annual curves and return levels under a wind climate, fragility curves and \
            Sobol indices. Long work (calibrations, validations, large sampling requests) runs as \
            operations: `202 Accepted` with `Location`, then poll or stream the operation. Errors are \
            RFC 9457 problem details naming the field at fault.",
        license(name = "MIT OR Apache-2.0", identifier = "MIT OR Apache-2.0"),
    ),
    tags(
        (name = "calibrations", description = "Fitting metamodels"),
        (name = "operations", description = "Long-running work: state, progress, cancellation"),
        (name = "metamodels", description = "Stored metamodels, exceedance curves, validations"),
        (name = "analyses", description = "Annual curves and return levels, fragility curves, Sobol indices"),
        (name = "presets", description = "Built-in studies"),
        (name = "health", description = "Liveness, readiness, metrics"),
    ),
    components(schemas(crate::service::error::ProblemDetails))
)]
struct ApiDoc;

/// The document before the routes add themselves.
pub fn base() -> utoipa::openapi::OpenApi {
    ApiDoc::openapi()
}

/// The complete API description of a server with the default settings, committed as
/// openapi/openapi.yaml.
pub fn openapi() -> utoipa::openapi::OpenApi {
    openapi_for(&ServeArgs::default())
}

/// The API description of a server with these settings, as it serves it at `/openapi.json`: the
/// limits an operator sets are the bounds its contract states.
pub fn openapi_for(config: &ServeArgs) -> utoipa::openapi::OpenApi {
    let (_, mut spec) = super::documented().split_for_parts();
    add_shared_responses(&mut spec);
    state_configured_limits(&mut spec, config);
    spec
}

/// The bounds that are settings of the server rather than constants of the code.
pub fn state_configured_limits(spec: &mut utoipa::openapi::OpenApi, config: &ServeArgs) {
    let experiments = config.max_experiments.min(crate::surrogate::MAX_EXPERIMENTS);
    set_maximum(spec, "CalibrationRequest", "experiments", experiments);
    set_maximum(spec, "ExceedanceRequest", "samples", config.max_samples.min(crate::analysis::MAX_SAMPLES));
    let reference_storms = config.max_reference_storms.min(crate::analysis::MAX_REFERENCE_STORMS);
    set_maximum(spec, "CertifyOptions", "reference_storms", reference_storms);
    let demand_samples = config.max_sync_samples.min(crate::service::demands::MAX_DEMAND_SAMPLES);
    set_maximum(spec, "DemandsRequest", "samples", demand_samples);
}

/// Sets the maximum of a request property, where the description has the request (a worker
/// replica describes only health and metrics).
fn set_maximum(spec: &mut utoipa::openapi::OpenApi, schema: &str, property: &str, maximum: usize) {
    let schemas = spec.components.as_mut().map(|c| &mut c.schemas);
    let Some(RefOr::T(Schema::Object(object))) = schemas.and_then(|s| s.get_mut(schema)) else {
        return;
    };
    let Some(RefOr::T(Schema::Object(field))) = object.properties.get_mut(property) else {
        panic!("{schema} has no property {property}");
    };
    field.maximum = Some((maximum as f64).into());
}

/// A shared error response: problem details with the given description.
fn problem_response(description: &str) -> Response {
    let content = ContentBuilder::new().schema(Some(Ref::from_schema_name("ProblemDetails"))).build();
    ResponseBuilder::new().description(description).content("application/problem+json", content).build()
}

/// The responses no handler writes itself, and the rule saying which operations can return them:
/// - every `/v1/` operation: 401 (when the server has API keys), and 500 (the database failed)
///   and 503 with `Retry-After` (the database does not answer now), except the presets, which
///   touch no database;
/// - every operation with a JSON body: 400 (malformed), 413 (too large), 415 (not JSON);
/// - every operation with query parameters: 400 (a value of the wrong type).
pub fn add_shared_responses(spec: &mut utoipa::openapi::OpenApi) {
    let components = spec.components.get_or_insert_with(Default::default);
    components.add_security_scheme("bearer", SecurityScheme::Http(Http::new(HttpAuthScheme::Bearer)));
    let shared = [
        ("BadRequest", "The body is not valid JSON, or a query parameter has the wrong type"),
        ("Unauthorized", "The server has API keys and the request has no valid `Authorization: Bearer` key"),
        ("PayloadTooLarge", "The body is larger than the server accepts"),
        ("UnsupportedMediaType", "The body is not `application/json`"),
        ("InternalError", "The server failed (the database); the error is logged"),
    ];
    for (name, description) in shared {
        components.responses.insert(name.to_string(), RefOr::T(problem_response(description)));
    }
    let mut unavailable = problem_response("The database does not answer now (restarting, unreachable or locked)");
    let retry_after = utoipa::openapi::HeaderBuilder::new()
        .schema(Some(ObjectBuilder::new().schema_type(Type::Integer).minimum(Some(0.0))))
        .description(Some("Seconds before asking again"))
        .build();
    unavailable.headers.insert("Retry-After".to_string(), RefOr::T(retry_after));
    components.responses.insert("DatabaseUnavailable".to_string(), RefOr::T(unavailable));
    components.schemas.insert("OperationEvent".to_string(), RefOr::T(crate::service::schema::operation_event_schema()));
    describe_event_stream(spec);
    for (path, item) in spec.paths.paths.iter_mut() {
        let operations = [&mut item.get, &mut item.post, &mut item.delete, &mut item.put, &mut item.patch];
        for operation in operations.into_iter().flatten() {
            add_to_operation(path, operation);
        }
    }
}

/// The event stream's records are `OperationEvent`s (the derive can only call the stream a string).
fn describe_event_stream(spec: &mut utoipa::openapi::OpenApi) {
    let events = spec.paths.paths.get_mut("/v1/operations/{id}/events").and_then(|item| item.get.as_mut());
    let stream =
        events.and_then(|operation| operation.responses.responses.get_mut("200")).and_then(|response| match response {
            RefOr::T(response) => response.content.get_mut("text/event-stream"),
            RefOr::Ref(_) => None,
        });
    if let Some(RefOr::T(content)) = stream {
        content.schema = Some(RefOr::Ref(Ref::from_schema_name("OperationEvent")));
    }
}

fn add_to_operation(path: &str, operation: &mut Operation) {
    let mut shared = Vec::new();
    if path.starts_with("/v1/") {
        shared.push(("401", "Unauthorized"));
        // An empty requirement besides the key: the server may run without keys.
        operation.security = Some(vec![SecurityRequirement::default(), SecurityRequirement::new("bearer", [""; 0])]);
        if !path.starts_with("/v1/presets") {
            shared.push(("500", "InternalError"));
            // Routes that document their own 503 (a full queue, no sampling permit) say there
            // that the database may be the reason too.
            if !operation.responses.responses.contains_key("503") {
                shared.push(("503", "DatabaseUnavailable"));
            }
        }
    }
    if operation.request_body.is_some() {
        shared.extend([("400", "BadRequest"), ("413", "PayloadTooLarge"), ("415", "UnsupportedMediaType")]);
    }
    let has_query = operation.parameters.iter().flatten().any(|p| match p {
        RefOr::T(parameter) => parameter.parameter_in == ParameterIn::Query,
        RefOr::Ref(_) => false,
    });
    if has_query {
        shared.push(("400", "BadRequest"));
    }
    for (status, name) in shared {
        operation.responses.responses.insert(status.to_string(), RefOr::Ref(Ref::from_response_name(name)));
    }
}
