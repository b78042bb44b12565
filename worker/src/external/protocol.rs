//! The strategy protocol's messages (`docs/strategy-protocol.md`, the users' spec) as types:
//! what floorcast sends ([`ToStrategy`]: hello, run, decide, end) and what a program writes
//! ([`FromStrategy`]: hello, ready, choose, rank, drop, goal, stop), one JSON object a line.
//!
//! A program's line is decoded once ([`Received::decode`]), then checked once against what it
//! answers: [`hello_of`] (the handshake), [`ready_of`] (the run message), [`reply_to`] (a
//! decision: ids offered, each once; a point of two finite numbers), which give the typed
//! [`Hello`] and [`Reply`] or the one-line error naming what was expected. The fields of a
//! program's message are decoded leniently ([`Field`]), so that a field of the wrong shape is
//! told by that check in the protocol's words, not by serde's.
//!
//! A message is written as its JSON value ([`line`]): serde_json's maps keep their keys sorted,
//! so every message's keys are in alphabetical order, `type` among them, as floorcast has always
//! written them. Floats are written in the shortest form that reads back bit for bit.
//!
//! Pure: no process, no IO.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::{Map, Value};
use sim_core::explore::{DecisionView, Reply, RoomState, RunEnd};
use sim_core::grid::{GridFrame, Occupancy};

use super::clip;

/// The newest protocol version this floorcast speaks (its hello says it); a program answers
/// with the version it speaks, [`OLDEST_PROTOCOL`] to this one. Version 2 adds the robot's
/// room to each decide message (`robot_room`, with the need "layout") and needs in the ready
/// reply, once the run's `params` are known.
pub const PROTOCOL_VERSION: u64 = 2;
/// The oldest protocol version this floorcast still speaks.
pub const OLDEST_PROTOCOL: u64 = 1;

/// A message floorcast sends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ToStrategy {
    /// The handshake: the protocol version and floorcast's.
    Hello { protocol: u64, floorcast: String },
    /// A run begins.
    Run(RunMessage),
    /// A decision (or an attempt at one) to make.
    Decide(DecideMessage),
    /// The run ended; no reply.
    End(EndMessage),
}

/// The run message's content.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunMessage {
    pub building: String,
    pub building_hash: String,
    pub seed: u64,
    /// [x m, y m, θ rad].
    pub start: [f64; 3],
    /// Every setting by name, in the units of the settings table.
    pub settings: Map<String, Value>,
    /// The strategy's own parameters.
    pub params: Map<String, Value>,
    pub map: MapMessage,
}

/// The map's grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapMessage {
    pub resolution_m: f64,
    pub width: u32,
    pub height: u32,
    /// The lower-left corner of cell (0, 0) (m).
    pub origin: [f64; 2],
}

/// The decide message's content.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecideMessage {
    pub decision: usize,
    pub attempt: usize,
    pub time_s: f64,
    /// [x m, y m, θ rad].
    pub pose: [f64; 3],
    pub candidates: Vec<CandidateMessage>,
    /// The previous attempt's goal point, when no drivable path led there.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unreachable_goal: Option<[f64; 2]>,
    /// With the need "layout", when a layout was made since the last decide message.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layout: Option<LayoutMessage>,
    /// With the need "map".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_changes: Option<MapChanges>,
    /// Protocol 2, with the need "layout" (`Some`): the index into the last layout's rooms of
    /// the predicted room holding the robot's estimated position, `null` when none does or no
    /// layout exists yet (`Some(None)`).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "present"
    )]
    pub robot_room: Option<Option<usize>>,
}

/// A candidate of a decide message.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateMessage {
    pub id: usize,
    pub cell: [i32; 2],
    pub point: [f64; 2],
    pub goal: [f64; 2],
    pub frontier_cells: usize,
    pub distance_m: f64,
    pub path_m: f64,
    pub straight_m: f64,
    pub gain_m2: f64,
    /// With the need "layout_gain" (`Some`), `null` until a layout exists (`Some(None)`).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "present"
    )]
    pub layout_gain_m2: Option<Option<f64>>,
    /// With the need "layout" (`Some`), `null` when no predicted room holds it (`Some(None)`).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "present"
    )]
    pub room: Option<Option<usize>>,
}

/// A field that is there, `null` or not (`null` is `Some(None)`).
fn present<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> Result<Option<Option<T>>, D::Error> {
    Option::<T>::deserialize(d).map(Some)
}

/// The layout predicted from the map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayoutMessage {
    pub number: u64,
    pub rooms: Vec<RoomMessage>,
}

/// A predicted room.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RoomMessage {
    pub polygon: Vec<[f64; 2]>,
    #[serde(with = "RoomStateName")]
    pub state: RoomState,
    pub predicted: bool,
    pub area_m2: f64,
    pub observed_area_m2: f64,
    pub unknown_area_m2: f64,
}

/// A room's state by its name ([`RoomState::as_str`]).
#[derive(Serialize, Deserialize)]
#[serde(remote = "RoomState", rename_all = "lowercase")]
enum RoomStateName {
    Full,
    Partial,
    Open,
}

/// The cells whose state changed since the last decide message, by index.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct MapChanges {
    pub free: Vec<usize>,
    pub occupied: Vec<usize>,
    pub unknown: Vec<usize>,
}

/// The end message's content.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EndMessage {
    #[serde(with = "crate::record::end_reason_name")]
    pub reason: sim_core::explore::EndReason,
    pub exploration_time_s: f64,
    pub explored_fraction: f64,
    pub decisions: usize,
}

impl ToStrategy {
    /// floorcast's hello.
    pub fn hello() -> Self {
        ToStrategy::Hello {
            protocol: PROTOCOL_VERSION,
            floorcast: crate::FLOORCAST_VERSION.to_string(),
        }
    }

    /// The end message of a run that ended so.
    pub fn end(end: &RunEnd) -> Self {
        ToStrategy::End(EndMessage {
            reason: end.reason,
            exploration_time_s: end.exploration_time_s,
            explored_fraction: end.explored_fraction,
            decisions: end.decisions,
        })
    }
}

/// The line that carries `msg`, its `\n` included: its JSON value, keys sorted (see the
/// module's docs).
pub fn line(msg: &ToStrategy) -> Result<String, serde_json::Error> {
    let mut line = serde_json::to_value(msg)?.to_string();
    line.push('\n');
    Ok(line)
}

/// The run message's content for a run of a strategy with `params`.
pub fn run_message(
    building_name: &str,
    building_hash: &str,
    seed: u64,
    start: sim_core::Pose,
    settings: &crate::Settings,
    params: &Map<String, Value>,
    frame: &GridFrame,
) -> RunMessage {
    RunMessage {
        building: building_name.to_string(),
        building_hash: building_hash.to_string(),
        seed,
        start: [start.x_m, start.y_m, start.theta_rad],
        settings: every_setting(settings),
        params: params.clone(),
        map: MapMessage {
            resolution_m: frame.resolution_m,
            width: frame.width,
            height: frame.height,
            origin: [frame.origin_m.x, frame.origin_m.y],
        },
    }
}

/// The settings with every key, those a summary leaves out at their defaults too.
fn every_setting(settings: &crate::Settings) -> Map<String, Value> {
    use crate::settings::{SettingKind, SettingValue, SETTINGS};
    let mut map = match serde_json::to_value(settings) {
        Ok(Value::Object(map)) => map,
        _ => Map::new(),
    };
    // The settings a record leaves out at their defaults.
    for info in SETTINGS {
        let value = match (settings.value(info.name), info.kind) {
            (Some(SettingValue::Number(x)), SettingKind::Integer { .. }) => Value::from(x as u64),
            (Some(SettingValue::Number(x)), _) => Value::from(x),
            (Some(SettingValue::Bool(b)), _) => Value::from(b),
            (Some(SettingValue::Word(w)), _) => Value::from(w),
            (None, _) => continue,
        };
        map.entry(info.name).or_insert(value);
    }
    map
}

/// What a program has been sent so far, for the next decide message: the map as last sent
/// (`map_changes` lists what differs) and the number of the last layout sent (0: none yet).
#[derive(Debug, Default)]
pub struct Sent {
    map: Vec<Occupancy>,
    layout: u64,
}

impl Sent {
    /// The decide message showing `view` to a program that said `hello`.
    pub fn decide(&mut self, view: &DecisionView<'_>, hello: &Hello) -> DecideMessage {
        let candidates = view
            .candidates
            .iter()
            .map(|c| CandidateMessage {
                id: c.id,
                cell: [c.cell.x, c.cell.y],
                point: [c.point.x, c.point.y],
                goal: [c.goal.x, c.goal.y],
                frontier_cells: c.frontier_cells,
                distance_m: c.distance_m,
                path_m: c.path_m,
                straight_m: c.straight_m,
                gain_m2: c.gain_m2,
                layout_gain_m2: hello.needs_layout_gain.then_some(c.layout_gain_m2),
                room: hello.needs_layout.then_some(c.room),
            })
            .collect();
        DecideMessage {
            decision: view.decision,
            attempt: view.attempt,
            time_s: view.time_s,
            pose: [view.pose.x_m, view.pose.y_m, view.pose.theta_rad],
            candidates,
            unreachable_goal: view.unreachable_goal.map(|p| [p.x, p.y]),
            layout: self.layout(view),
            map_changes: hello.needs_map.then(|| self.map_changes(view)),
            robot_room: (hello.protocol >= 2 && hello.needs_layout).then(|| {
                view.layout
                    .and_then(|l| l.room_holding(view.pose.position()))
            }),
        }
    }

    /// The view's layout, unless it was sent already.
    fn layout(&mut self, view: &DecisionView<'_>) -> Option<LayoutMessage> {
        let layout = view.layout.filter(|l| l.number != self.layout)?;
        self.layout = layout.number;
        let rooms = layout
            .rooms
            .iter()
            .map(|r| RoomMessage {
                polygon: r.polygon.iter().map(|p| [p.x, p.y]).collect(),
                state: r.state,
                predicted: r.predicted,
                area_m2: r.area_m2,
                observed_area_m2: r.observed_area_m2,
                unknown_area_m2: r.unknown_area_m2,
            })
            .collect();
        Some(LayoutMessage {
            number: layout.number,
            rooms,
        })
    }

    /// The cells of the view's map that differ from those sent (all unknown at first).
    fn map_changes(&mut self, view: &DecisionView<'_>) -> MapChanges {
        let data = &view.map.data;
        if self.map.len() != data.len() {
            self.map = vec![Occupancy::Unknown; data.len()];
        }
        let mut changes = MapChanges::default();
        for (i, (now, sent)) in data.iter().zip(self.map.iter_mut()).enumerate() {
            if now != sent {
                match now {
                    Occupancy::Free => changes.free.push(i),
                    Occupancy::Occupied => changes.occupied.push(i),
                    Occupancy::Unknown => changes.unknown.push(i),
                }
                *sent = *now;
            }
        }
        changes
    }
}

/// A message a program writes. Its fields are [`Field`]s: whatever a program writes in them
/// decodes, and the check of what it answers ([`hello_of`], [`reply_to`]) says what was
/// expected. Fields not listed are ignored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum FromStrategy {
    /// The program's hello: the protocol it speaks, its name, what it needs.
    Hello {
        #[serde(default, skip_serializing_if = "Field::is_missing")]
        protocol: Field<u64>,
        #[serde(default, skip_serializing_if = "Field::is_missing")]
        name: Field<String>,
        #[serde(default, skip_serializing_if = "Field::is_missing")]
        needs: Field<Vec<Field<Need>>>,
    },
    /// Ready for the run; in protocol 2, with the run's needs (replacing the hello's).
    Ready {
        #[serde(default, skip_serializing_if = "Field::is_missing")]
        needs: Field<Vec<Field<Need>>>,
    },
    /// Drive to this candidate.
    Choose {
        #[serde(default, skip_serializing_if = "Field::is_missing")]
        id: Field<u64>,
    },
    /// Try these candidates in this order.
    Rank {
        #[serde(default, skip_serializing_if = "Field::is_missing")]
        ids: Field<Vec<u64>>,
    },
    /// Give these candidates up.
    Drop {
        #[serde(default, skip_serializing_if = "Field::is_missing")]
        ids: Field<Vec<u64>>,
    },
    /// Drive to this point (m, map frame).
    Goal {
        #[serde(default, skip_serializing_if = "Field::is_missing")]
        point: Field<[f64; 2]>,
    },
    /// End the exploration.
    Stop,
}

/// What a program may need besides the candidates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Need {
    LayoutGain,
    Layout,
    Map,
}

/// A field of a program's message: absent (or `null`), a `T`, or something else, kept for the
/// message that says so.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Field<T> {
    #[default]
    Missing,
    Given(T),
    Wrong(Value),
}

impl<T> Field<T> {
    fn is_missing(&self) -> bool {
        matches!(self, Field::Missing)
    }
}

impl<'de, T: serde::de::DeserializeOwned> Deserialize<'de> for Field<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        if v.is_null() {
            return Ok(Field::Missing);
        }
        Ok(T::deserialize(&v).map_or(Field::Wrong(v), Field::Given))
    }
}

impl<T: Serialize> Serialize for Field<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Field::Missing => s.serialize_none(),
            Field::Given(t) => t.serialize(s),
            Field::Wrong(v) => v.serialize(s),
        }
    }
}

/// A line a program wrote, a JSON object: the message it is (`None`: its `type` is none of
/// the protocol's) and the object as written, quoted in errors.
#[derive(Debug, Clone, PartialEq)]
pub struct Received {
    pub message: Option<FromStrategy>,
    value: Value,
}

impl Received {
    /// The line as a message (`None`: not a JSON object).
    pub fn decode(line: &str) -> Option<Received> {
        let value = serde_json::from_str::<Value>(line)
            .ok()
            .filter(Value::is_object)?;
        Some(Received {
            message: FromStrategy::deserialize(&value).ok(),
            value,
        })
    }

    /// The object, for a message: compact JSON, keys sorted, at most 80 bytes.
    pub fn quoted(&self) -> String {
        quote_json(&self.value)
    }
}

fn quote_json(v: &Value) -> String {
    clip(&v.to_string(), 80)
}

/// What the program said of itself (its needs as its ready reply set them, in protocol 2).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Hello {
    /// The protocol version it speaks.
    pub protocol: u64,
    pub name: String,
    pub needs_layout_gain: bool,
    pub needs_layout: bool,
    pub needs_map: bool,
}

/// The program's answer to floorcast's hello, checked: the protocol version, a name of 1 to
/// 100 characters (not only whitespace, no control characters), needs floorcast offers.
pub fn hello_of(r: &Received) -> Result<Hello, String> {
    let what = || format!("answered the hello message with {}", r.quoted());
    let Some(FromStrategy::Hello {
        protocol,
        name,
        needs,
    }) = &r.message
    else {
        return Err(format!("{} (expected a hello message)", what()));
    };
    let protocol = match protocol {
        Field::Given(p) if (OLDEST_PROTOCOL..=PROTOCOL_VERSION).contains(p) => *p,
        Field::Given(p) => {
            return Err(format!(
                "speaks protocol version {p}; this floorcast speaks versions {OLDEST_PROTOCOL} to {PROTOCOL_VERSION} (docs/strategy-protocol.md)"
            ))
        }
        _ => {
            return Err(format!(
                "{} (expected \"protocol\": {OLDEST_PROTOCOL} to {PROTOCOL_VERSION})",
                what()
            ))
        }
    };
    let name = match name {
        Field::Given(n) => n.as_str(),
        _ => "",
    };
    if name.trim().is_empty() || name.chars().count() > 100 || name.chars().any(char::is_control) {
        return Err(format!(
            "{} (expected \"name\": a non-empty string of at most 100 characters, no control characters)",
            what()
        ));
    }
    let mut hello = Hello {
        protocol,
        name: name.to_string(),
        ..Hello::default()
    };
    hello.set_needs(&needs_of(needs)?);
    Ok(hello)
}

impl Hello {
    /// Needs exactly `needs`.
    fn set_needs(&mut self, needs: &[Need]) {
        self.needs_layout_gain = needs.contains(&Need::LayoutGain);
        self.needs_layout = needs.contains(&Need::Layout);
        self.needs_map = needs.contains(&Need::Map);
    }
}

/// The needs a hello lists (none when it has no `needs`).
fn needs_of(needs: &Field<Vec<Field<Need>>>) -> Result<Vec<Need>, String> {
    match needs {
        Field::Missing => Ok(Vec::new()),
        Field::Given(list) => list
            .iter()
            .map(|n| match n {
                Field::Given(need) => Ok(*need),
                Field::Missing => Err(Value::Null),
                Field::Wrong(v) => Err(v.clone()),
            })
            .collect::<Result<_, _>>()
            .map_err(|v| {
                format!(
                    "needs {} (floorcast offers \"layout_gain\", \"layout\" and \"map\")",
                    quote_json(&v)
                )
            }),
        Field::Wrong(other) => Err(format!(
            "gave \"needs\": {} (expected a list such as [\"layout_gain\", \"map\"])",
            quote_json(other)
        )),
    }
}

/// The program's answer to the run message, checked: ready. In protocol 2, needs it lists
/// replace those of its hello (they may depend on the run's `params`); in protocol 1 `needs`
/// is refused (version 2 added it: ignoring it would run without what the program asked
/// for), other fields are ignored.
pub fn ready_of(r: &Received, hello: &mut Hello) -> Result<(), String> {
    match &r.message {
        Some(FromStrategy::Ready { needs }) => {
            if hello.protocol < 2 && !needs.is_missing() {
                return Err(format!(
                    "answered the run message with \"needs\" in its ready reply, which protocol version 2 added, but its hello said it speaks version {}: say \"protocol\": 2 in the hello reply, or leave \"needs\" out of the ready reply (the hello's needs then hold; docs/strategy-protocol.md)",
                    hello.protocol
                ));
            }
            if !needs.is_missing() {
                let needs =
                    needs_of(needs).map_err(|e| format!("answered the run message: {e}"))?;
                hello.set_needs(&needs);
            }
            Ok(())
        }
        _ => Err(format!(
            "answered the run message with {} (expected {{\"type\":\"ready\"}})",
            r.quoted()
        )),
    }
}

/// The program's answer to the decide message showing `view` (`what` names it: "decision
/// 4"), checked against it: a choice or a ranking of candidates offered (each once), a drop
/// of such, a point of its own (two finite numbers), or a stop.
pub fn reply_to(r: &Received, view: &DecisionView<'_>, what: &str) -> Result<Reply, String> {
    let expected = |field: &str| format!("answered {what} with {} (expected {field})", r.quoted());
    let offered = |id: u64| view.candidates.iter().any(|c| c.id as u64 == id);
    let ids = || {
        let ids: Vec<String> = view.candidates.iter().map(|c| c.id.to_string()).collect();
        clip(&ids.join(", "), 80)
    };
    match &r.message {
        Some(FromStrategy::Choose { id }) => match id {
            Field::Given(id) if offered(*id) => Ok(Reply::Choose(*id as usize)),
            Field::Given(id) => Err(format!(
                "chose candidate {id}, which {what} did not offer (it offered {})",
                ids()
            )),
            _ => Err(expected("\"id\": one of the candidates' ids")),
        },
        Some(FromStrategy::Rank { ids: list } | FromStrategy::Drop { ids: list }) => {
            let rank = matches!(r.message, Some(FromStrategy::Rank { .. }));
            let verb = if rank { "ranked" } else { "dropped" };
            let Field::Given(list) = list.clone() else {
                return Err(expected("\"ids\": a non-empty list of candidate ids"));
            };
            if list.is_empty() {
                return Err(expected("\"ids\": a non-empty list of candidate ids"));
            }
            let mut seen = std::collections::BTreeSet::new();
            for &id in &list {
                if !offered(id) {
                    return Err(format!(
                        "{verb} candidate {id}, which {what} did not offer (it offered {})",
                        ids()
                    ));
                }
                if !seen.insert(id) {
                    return Err(format!("{verb} candidate {id} twice in {what}"));
                }
            }
            let list = list.into_iter().map(|i| i as usize).collect();
            Ok(if rank {
                Reply::Rank(list)
            } else {
                Reply::Drop(list)
            })
        }
        Some(FromStrategy::Goal {
            point: Field::Given([x, y]),
        }) if x.is_finite() && y.is_finite() => Ok(Reply::Goal(sim_core::Vec2::new(*x, *y))),
        Some(FromStrategy::Goal { .. }) => {
            Err(expected("\"point\": [x, y], metres in the map frame"))
        }
        Some(FromStrategy::Stop) => Ok(Reply::Stop),
        _ => Err(expected("a choose, rank, goal, drop or stop message")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim_core::explore::{CandidateView, EndReason, LayoutView, RoomView};
    use sim_core::grid::{Cell, OccupancyGrid};
    use sim_core::Vec2;

    #[test]
    fn the_run_message_carries_every_setting() {
        let v = every_setting(&crate::Settings::default());
        for s in crate::settings::SETTINGS {
            assert!(v.get(s.name).is_some(), "{} missing", s.name);
        }
    }

    fn candidate(id: usize, x: i32) -> CandidateView {
        CandidateView {
            id,
            cell: Cell::new(x, 1),
            point: Vec2::new(0.1 * x as f64, 0.25),
            goal: Vec2::new(0.1 * x as f64, 0.3),
            frontier_cells: 4,
            distance_m: 1.5,
            path_m: 1.5,
            straight_m: 1.0 / 3.0,
            gain_m2: 2.0,
            layout_gain_m2: (id == 0).then_some(0.75),
            room: (id == 0).then_some(0),
        }
    }

    fn map() -> OccupancyGrid {
        OccupancyGrid::from_ascii("\n  ?#.\n  ..?\n  ", 0.5)
    }

    fn room() -> RoomView {
        RoomView {
            polygon: vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
            ],
            state: RoomState::Partial,
            predicted: true,
            area_m2: 0.5,
            observed_area_m2: 0.25,
            unknown_area_m2: 0.125,
        }
    }

    fn view<'a>(
        candidates: &'a [CandidateView],
        rooms: &'a [RoomView],
        map: &'a OccupancyGrid,
    ) -> DecisionView<'a> {
        DecisionView {
            decision: 3,
            attempt: 1,
            time_s: 12.5,
            pose: sim_core::Pose::new(1.0, -2.0, 0.1),
            candidates,
            unreachable_goal: Some(Vec2::new(4.5, 2.0)),
            layout: Some(LayoutView { number: 2, rooms }),
            map,
            between_m: None,
            team: None,
        }
    }

    fn text(msg: &ToStrategy) -> String {
        line(msg).unwrap()
    }

    /// The bytes floorcast has always sent: keys in alphabetical order (`type` among them),
    /// optional fields only when asked for, `null` for a need without a value yet, floats in
    /// their shortest round-trip form.
    #[test]
    fn messages_are_written_as_they_always_were() {
        let hello = text(&ToStrategy::hello());
        let version = crate::FLOORCAST_VERSION;
        assert_eq!(
            hello,
            format!("{{\"floorcast\":\"{version}\",\"protocol\":2,\"type\":\"hello\"}}\n")
        );
        let (cs, rooms, map) = ([candidate(0, 2), candidate(4, 1)], [room()], map());
        let all = Hello {
            protocol: 1,
            name: "x".into(),
            needs_layout_gain: true,
            needs_layout: true,
            needs_map: true,
        };
        let mut sent = Sent::default();
        let decide = text(&ToStrategy::Decide(
            sent.decide(&view(&cs, &rooms, &map), &all),
        ));
        assert_eq!(
            decide,
            concat!(
                r#"{"attempt":1,"candidates":[{"cell":[2,1],"distance_m":1.5,"frontier_cells":4,"#,
                r#""gain_m2":2.0,"goal":[0.2,0.3],"id":0,"layout_gain_m2":0.75,"path_m":1.5,"#,
                r#""point":[0.2,0.25],"room":0,"straight_m":0.3333333333333333},"#,
                r#"{"cell":[1,1],"distance_m":1.5,"frontier_cells":4,"gain_m2":2.0,"#,
                r#""goal":[0.1,0.3],"id":4,"layout_gain_m2":null,"path_m":1.5,"point":[0.1,0.25],"#,
                r#""room":null,"straight_m":0.3333333333333333}],"decision":3,"#,
                r#""layout":{"number":2,"rooms":[{"area_m2":0.5,"observed_area_m2":0.25,"#,
                r#""polygon":[[0.0,0.0],[1.0,0.0],[1.0,1.0]],"predicted":true,"state":"partial","#,
                r#""unknown_area_m2":0.125}]},"map_changes":{"free":[0,1,5],"occupied":[4],"#,
                r#""unknown":[]},"pose":[1.0,-2.0,0.1],"time_s":12.5,"type":"decide","#,
                r#""unreachable_goal":[4.5,2.0]}"#,
                "\n"
            )
        );
        // The same layout and map are not sent again; without needs, neither they nor the
        // layout's fields are.
        let again = sent.decide(&view(&cs, &rooms, &map), &all);
        assert!(again.layout.is_none());
        assert_eq!(again.map_changes, Some(MapChanges::default()));
        let none = Sent::default().decide(&view(&cs, &rooms, &map), &Hello::default());
        let none = text(&ToStrategy::Decide(none));
        assert!(
            !none.contains("layout_gain_m2") && !none.contains("\"room\""),
            "{none}"
        );
        assert!(!none.contains("map_changes"), "{none}");
        // Protocol 2 adds the robot's room with the need "layout": null outside every room,
        // else the room's index; not without the need.
        let v2 = Hello {
            protocol: 2,
            ..all.clone()
        };
        let outside = Sent::default().decide(&view(&cs, &rooms, &map), &v2);
        assert_eq!(outside.robot_room, Some(None));
        assert!(text(&ToStrategy::Decide(outside)).contains(r#""robot_room":null,"#));
        let mut inside = view(&cs, &rooms, &map);
        inside.pose = sim_core::Pose::new(0.8, 0.2, 0.0);
        assert_eq!(
            Sent::default().decide(&inside, &v2).robot_room,
            Some(Some(0))
        );
        let unasked = Hello {
            needs_layout: false,
            ..v2.clone()
        };
        assert_eq!(Sent::default().decide(&inside, &unasked).robot_room, None);
        let end = text(&ToStrategy::end(&RunEnd {
            reason: EndReason::EarlyStop,
            exploration_time_s: 812.4,
            explored_fraction: 0.991,
            decisions: 57,
        }));
        assert_eq!(
            end,
            concat!(
                r#"{"decisions":57,"exploration_time_s":812.4,"explored_fraction":0.991,"#,
                r#""reason":"early stop","type":"end"}"#,
                "\n"
            )
        );
    }

    #[test]
    fn the_run_message_is_written_as_it_always_was() {
        let frame = GridFrame::new(Vec2::new(-8.0, -6.5), 0.05, 812, 640);
        let mut params = Map::new();
        params.insert("stop_below_m2".into(), Value::from(5));
        let run = run_message(
            "Franch1",
            "3f9a",
            3,
            sim_core::Pose::new(4.2, 7.5, 1.5),
            &crate::Settings::default(),
            &params,
            &frame,
        );
        let text = text(&ToStrategy::Run(run));
        assert!(
            text.starts_with(r#"{"building":"Franch1","building_hash":"3f9a","map":{"height":640,"origin":[-8.0,-6.5],"resolution_m":0.05,"width":812},"params":{"stop_below_m2":5},"seed":3,"settings":{"#),
            "{text}"
        );
        assert!(
            text.ends_with("},\"start\":[4.2,7.5,1.5],\"type\":\"run\"}\n"),
            "{text}"
        );
    }

    fn reply(line: &str) -> Result<Reply, String> {
        let (cs, rooms, map) = ([candidate(0, 2), candidate(4, 1)], [room()], map());
        let r = Received::decode(line).expect("a JSON object");
        reply_to(&r, &view(&cs, &rooms, &map), "decision 3")
    }

    /// Replies refused, and words of what is said.
    const REFUSED_REPLIES: [(&str, &str); 18] = [
        (
            r#"{"type":"choose","id":3.0}"#,
            r#"answered decision 3 with {"id":3.0,"type":"choose"} (expected "id": one of the candidates' ids)"#,
        ),
        (
            r#"{"type":"choose","id":"4"}"#,
            r#"(expected "id": one of the candidates' ids)"#,
        ),
        (
            r#"{"type":"choose","id":-1}"#,
            r#"(expected "id": one of the candidates' ids)"#,
        ),
        (
            r#"{"type":"choose"}"#,
            r#"(expected "id": one of the candidates' ids)"#,
        ),
        (
            r#"{"type":"choose","id":2}"#,
            "chose candidate 2, which decision 3 did not offer (it offered 0, 4)",
        ),
        (
            r#"{"type":"rank","ids":[]}"#,
            r#"(expected "ids": a non-empty list of candidate ids)"#,
        ),
        (
            r#"{"type":"rank","ids":[0,"4"]}"#,
            r#"(expected "ids": a non-empty list of candidate ids)"#,
        ),
        (
            r#"{"type":"drop","ids":4}"#,
            r#"(expected "ids": a non-empty list of candidate ids)"#,
        ),
        (
            r#"{"type":"rank","ids":[4,4]}"#,
            "ranked candidate 4 twice in decision 3",
        ),
        (
            r#"{"type":"drop","ids":[0,9]}"#,
            "dropped candidate 9, which decision 3 did not offer (it offered 0, 4)",
        ),
        (
            r#"{"type":"goal","point":"here"}"#,
            r#"answered decision 3 with {"point":"here","type":"goal"} (expected "point": [x, y], metres in the map frame)"#,
        ),
        (
            r#"{"type":"goal","point":[1,2,3]}"#,
            r#"(expected "point": [x, y]"#,
        ),
        (
            r#"{"type":"goal","point":[1,null]}"#,
            r#"(expected "point": [x, y]"#,
        ),
        (
            r#"{"type":"ready"}"#,
            r#"answered decision 3 with {"type":"ready"} (expected a choose, rank, goal, drop or stop message)"#,
        ),
        (
            r#"{"type":"hello","protocol":1}"#,
            "(expected a choose, rank, goal, drop or stop message)",
        ),
        (
            r#"{"type":"pick","id":0}"#,
            "(expected a choose, rank, goal, drop or stop message)",
        ),
        (
            r#"{"type":4}"#,
            "(expected a choose, rank, goal, drop or stop message)",
        ),
        (
            r#"{"id":0}"#,
            "(expected a choose, rank, goal, drop or stop message)",
        ),
    ];

    /// A reply is decoded into its type, then checked against the decision: what is refused
    /// says what was expected, in the protocol's words.
    #[test]
    fn replies_are_checked_against_the_decision() {
        let ok: [(&str, Reply); 7] = [
            (r#"{"type":"choose","id":4}"#, Reply::Choose(4)),
            (r#"{"type":"choose","id":4,"why":"near"}"#, Reply::Choose(4)),
            (r#"{"type":"rank","ids":[4,0]}"#, Reply::Rank(vec![4, 0])),
            (r#"{"type":"drop","ids":[0]}"#, Reply::Drop(vec![0])),
            (
                r#"{"type":"goal","point":[4,2.5]}"#,
                Reply::Goal(Vec2::new(4.0, 2.5)),
            ),
            (r#"{"type":"stop"}"#, Reply::Stop),
            (r#"{"type":"stop","because":[1]}"#, Reply::Stop),
        ];
        for (line, want) in ok {
            assert_eq!(reply(line), Ok(want), "{line}");
        }
        let refused = REFUSED_REPLIES;
        for (line, want) in refused {
            let e = reply(line).expect_err(line);
            assert!(e.contains(want), "{line}: {e}");
        }
        for line in ["this is not json", "[1, 2]", "3", "\"choose\""] {
            assert_eq!(Received::decode(line), None, "{line}");
        }
    }

    fn hello(line: &str) -> Result<Hello, String> {
        hello_of(&Received::decode(line).expect("a JSON object"))
    }

    #[test]
    fn a_hello_is_checked() {
        let h = hello(r#"{"type":"hello","protocol":1,"name":"n","needs":["map","layout"],"x":1}"#);
        let want = Hello {
            protocol: 1,
            name: "n".into(),
            needs_layout_gain: false,
            needs_layout: true,
            needs_map: true,
        };
        assert_eq!(h, Ok(want));
        for line in [
            r#"{"type":"hello","protocol":1,"name":"n"}"#,
            r#"{"type":"hello","protocol":1,"name":"n","needs":null}"#,
            r#"{"type":"hello","protocol":1,"name":"n","needs":[]}"#,
        ] {
            assert_eq!(hello(line).map(|h| h.needs_map), Ok(false), "{line}");
        }
        let refused = [
            (r#"{"type":"ready"}"#, r#"answered the hello message with {"type":"ready"} (expected a hello message)"#),
            (r#"{"protocol":1,"name":"n"}"#, "(expected a hello message)"),
            (r#"{"type":"hello","protocol":99,"name":"n"}"#, "speaks protocol version 99; this floorcast speaks versions 1 to 2 (docs/strategy-protocol.md)"),
            (r#"{"type":"hello","protocol":0,"name":"n"}"#, "speaks protocol version 0; this floorcast speaks versions 1 to 2"),
            (r#"{"type":"hello","protocol":1.0,"name":"n"}"#, r#"(expected "protocol": 1 to 2)"#),
            (r#"{"type":"hello","name":"n"}"#, r#"(expected "protocol": 1 to 2)"#),
            (r#"{"type":"hello","protocol":1}"#, r#"(expected "name": a non-empty string"#),
            (r#"{"type":"hello","protocol":1,"name":"  "}"#, r#"(expected "name": a non-empty string"#),
            (r#"{"type":"hello","protocol":1,"name":"a\u0007"}"#, "no control characters)"),
            (r#"{"type":"hello","protocol":1,"name":7}"#, r#"(expected "name""#),
            (r#"{"type":"hello","protocol":1,"name":"n","needs":"map"}"#, r#"gave "needs": "map" (expected a list such as ["layout_gain", "map"])"#),
            (r#"{"type":"hello","protocol":1,"name":"n","needs":["maps"]}"#, r#"needs "maps" (floorcast offers "layout_gain", "layout" and "map")"#),
            (r#"{"type":"hello","protocol":1,"name":"n","needs":[null]}"#, "needs null (floorcast offers"),
            (r#"{"type":"hello","protocol":1,"name":"n","needs":[3]}"#, "needs 3 (floorcast offers"),
        ];
        for (line, want) in refused {
            let e = hello(line).expect_err(line);
            assert!(e.contains(want), "{line}: {e}");
        }
        let long = format!(
            r#"{{"type":"hello","protocol":1,"name":"{}"}}"#,
            "x".repeat(101)
        );
        assert!(hello(&long).is_err());
        let ready = |line, h: &mut Hello| ready_of(&Received::decode(line).unwrap(), h);
        let mut h = hello(r#"{"type":"hello","protocol":1,"name":"n","needs":["map"]}"#).unwrap();
        assert_eq!(ready(r#"{"type":"ready","x":[]}"#, &mut h), Ok(()));
        let e = ready(r#"{"type":"choose","id":1}"#, &mut h).unwrap_err();
        assert_eq!(
            e,
            r#"answered the run message with {"id":1,"type":"choose"} (expected {"type":"ready"})"#
        );
        // Needs in the ready reply: refused in protocol 1 (whatever their value; null is no
        // needs), the run's
        // needs in protocol 2 (replacing the hello's; none listed keeps them).
        let v1 = h.clone();
        for line in [
            r#"{"type":"ready","needs":["layout"]}"#,
            r#"{"type":"ready","needs":[]}"#,
            r#"{"type":"ready","needs":"map"}"#,
        ] {
            let e = ready(line, &mut h).unwrap_err();
            assert!(
                e.contains(r#"answered the run message with "needs" in its ready reply, which protocol version 2 added, but its hello said it speaks version 1: say "protocol": 2"#),
                "{line}: {e}"
            );
            assert_eq!(h, v1, "{line}");
        }
        assert_eq!(ready(r#"{"type":"ready","needs":null}"#, &mut h), Ok(()));
        let mut h = hello(r#"{"type":"hello","protocol":2,"name":"n","needs":["map"]}"#).unwrap();
        assert_eq!(ready(r#"{"type":"ready"}"#, &mut h), Ok(()));
        assert!(h.needs_map && !h.needs_layout);
        assert_eq!(
            ready(
                r#"{"type":"ready","needs":["layout","layout_gain"]}"#,
                &mut h
            ),
            Ok(())
        );
        assert!(!h.needs_map && h.needs_layout && h.needs_layout_gain);
        assert_eq!(ready(r#"{"type":"ready","needs":[]}"#, &mut h), Ok(()));
        assert!(!h.needs_map && !h.needs_layout && !h.needs_layout_gain);
        let e = ready(r#"{"type":"ready","needs":["maps"]}"#, &mut h).unwrap_err();
        assert!(
            e.contains(r#"answered the run message: needs "maps" (floorcast offers"#),
            "{e}"
        );
    }
}
