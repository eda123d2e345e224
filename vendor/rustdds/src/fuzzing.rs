//! Entry point for fuzzing the receive path (patch for gspn, not part of the
//! RustDDS API; hidden from the docs).
//!
//! [`receive`] hands one datagram to a [`MessageReceiver`] exactly as the
//! event loop does with every datagram its UDP listeners read
//! (`handle_received_packet`), after setting up the state a running
//! participant would have once it discovered the sender: the standard
//! built-in readers (SPDP, SEDP publications / subscriptions / topics,
//! participant messages) with the QoS Discovery gives them, and a user reader
//! for every user-defined reader the packet names, each matched with the
//! writers of the packet's sender(s) (INFO_SOURCE may name several). So DATA,
//! DATA_FRAG, HEARTBEAT and GAP reach the writer proxies and history caches
//! instead of being dropped as coming from unknown writers. The serialized
//! payloads of DATA sent to the built-in readers are then deserialized as
//! Discovery does (SPDP participant data, SEDP reader / writer / topic data).
//!
//! ACKNACKs the readers send go through a UDP sender bound to 127.0.0.1: run a
//! fuzzer in a network namespace of its own so they reach nobody.
use std::{
  cell::RefCell,
  collections::BTreeSet,
  net::{IpAddr, Ipv4Addr},
  rc::Rc,
  sync::{Arc, Mutex, RwLock},
};

use bytes::Bytes;

use crate::{
  dds::{
    qos::{policy, QosPolicies, QosPolicyBuilder},
    statusevents::{sync_status_channel, DataReaderStatus},
    typedesc::TypeDesc,
    with_key::simpledatareader::ReaderCommand,
  },
  discovery::{
    discovery::Discovery,
    sedp_messages::{DiscoveredReaderData, DiscoveredTopicData, DiscoveredWriterData},
    spdp_participant_data::SpdpDiscoveredParticipantData,
  },
  messages::submessages::{
    elements::serialized_payload::SerializedPayload,
    submessage::{InterpreterSubmessage, WriterSubmessage},
  },
  mio_source,
  network::{udp_listener::PacketOrigin, udp_sender::UDPSender},
  polling::{new_shared_timer, wake_channel, LoopWaker},
  rtps::{
    constant::STANDARD_BUILTIN_READERS_INIT_LIST,
    message_receiver::MessageReceiver,
    reader::{Reader, ReaderIngredients},
    rtps_writer_proxy::RtpsWriterProxy,
    transmit::InterfaceObservations,
    Message, SubmessageBody,
  },
  serialization::pl_cdr_adapters::PlCdrDeserialize,
  structure::{
    dds_cache::DDSCache,
    guid::{EntityId, EntityKind, GuidPrefix, GUID},
  },
};

/// The receiving participant's GUID prefix.
const OWN_PREFIX: [u8; 12] = *b"gspn-fuzzing";

/// At most this many user readers are created for one packet.
const MAX_USER_READERS: usize = 8;

thread_local! {
  // One sender per thread: binding a socket per datagram would dominate the run.
  static SENDER: Rc<UDPSender> = Rc::new(
    UDPSender::new_with_networks(
      0,
      Some(&[IpAddr::V4(Ipv4Addr::LOCALHOST)]),
      0,
      Some(IpAddr::V4(Ipv4Addr::LOCALHOST)),
    )
    .expect("a UDP socket on 127.0.0.1"),
  );
}

/// What the packet names: the senders' GUID prefixes, the user-defined
/// readers it addresses and the writers (with their prefixes) it speaks for.
struct Named {
  writers: BTreeSet<GUID>,
  user_readers: BTreeSet<EntityId>,
}

fn named(message: &Message) -> Named {
  let mut prefix = message.header.guid_prefix;
  let mut writers = BTreeSet::new();
  let mut user_readers = BTreeSet::new();
  for sub in &message.submessages {
    let (reader_id, writer_id) = match &sub.body {
      SubmessageBody::Interpreter(InterpreterSubmessage::InfoSource(info, _)) => {
        prefix = info.guid_prefix;
        continue;
      }
      SubmessageBody::Writer(WriterSubmessage::Data(d, _)) => (d.reader_id, d.writer_id),
      SubmessageBody::Writer(WriterSubmessage::DataFrag(d, _)) => (d.reader_id, d.writer_id),
      SubmessageBody::Writer(WriterSubmessage::Gap(g, _)) => (g.reader_id, g.writer_id),
      SubmessageBody::Writer(WriterSubmessage::Heartbeat(h, _)) => (h.reader_id, h.writer_id),
      _ => continue,
    };
    writers.insert(GUID::new(prefix, writer_id));
    if reader_id.kind().is_user_defined() && user_readers.len() < MAX_USER_READERS {
      user_readers.insert(reader_id);
    }
  }
  if user_readers.is_empty() {
    // DATA to ENTITYID_UNKNOWN goes to every reader matched with the writer.
    user_readers.insert(EntityId::new(
      [0, 0, 1],
      EntityKind::READER_NO_KEY_USER_DEFINED,
    ));
  }
  Named {
    writers,
    user_readers,
  }
}

/// Discovery matched `writer` with `reader` (no locators: replies go to the
/// packet's INFO_REPLY locators, if any).
fn matched(reader: &mut Reader, writer: GUID, qos: &QosPolicies) {
  let proxy = RtpsWriterProxy::new(writer, vec![], vec![], EntityId::UNKNOWN);
  reader.update_writer_proxy(proxy, qos);
}

/// A reader of topic `name` with `qos`, as the event loop creates it from a
/// DataReader's ingredients.
fn reader(dds_cache: &RwLock<DDSCache>, entity_id: EntityId, name: &str, qos: QosPolicies) -> Reader {
  let (notification_sender, _) = mio_source::notification_channel(16);
  let (_, poll_event_sender) = mio_source::make_poll_channel().expect("a poll channel");
  let (status_sender, _) = sync_status_channel::<DataReaderStatus>(4).expect("a status channel");
  let (participant_status_sender, _) = sync_status_channel(16).expect("a status channel");
  let (_, data_reader_command_receiver) = wake_channel::<ReaderCommand>(4, &LoopWaker::new());
  let topic_cache_handle = dds_cache.write().unwrap().add_new_topic(
    name.to_string(),
    TypeDesc::new(name.to_string()),
    &qos,
  );
  let ingredients = ReaderIngredients {
    guid: GUID::new(GuidPrefix::new(&OWN_PREFIX), entity_id),
    notification_sender,
    status_sender,
    topic_name: name.to_string(),
    topic_cache_handle,
    like_stateless: false,
    qos_policy: qos,
    data_reader_command_receiver,
    data_reader_waker: Arc::new(Mutex::new(None)),
    poll_event_sender,
    security_plugins: None,
    discovery_notify: None,
  };
  Reader::new(
    ingredients,
    SENDER.with(Rc::clone),
    new_shared_timer(),
    participant_status_sender,
  )
}

/// One datagram through the receive path of a participant that knows its
/// sender (see the module's doc). Never panics on any input unless RustDDS
/// has a bug.
pub fn receive(datagram: &[u8]) {
  let bytes = Bytes::copy_from_slice(datagram);
  let parsed = Message::read_from_buffer(&bytes).ok();

  let waker = LoopWaker::new();
  let (acknack_sender, _acknack_receiver) = wake_channel(64, &waker);
  let (spdp_liveness_sender, _spdp_liveness_receiver) = wake_channel(64, &waker);
  let mut receiver = MessageReceiver::new(
    GuidPrefix::new(&OWN_PREFIX),
    acknack_sender,
    spdp_liveness_sender,
    None,
    Rc::new(RefCell::new(InterfaceObservations::new())),
  );
  let dds_cache = Arc::new(RwLock::new(DDSCache::new()));
  let named = parsed.as_ref().map(named);
  let writers = named.as_ref().map(|n| &n.writers);

  for (i, (writer_id, reader_id, _, _)) in STANDARD_BUILTIN_READERS_INIT_LIST.iter().enumerate() {
    let qos = if *reader_id == EntityId::SPDP_BUILTIN_PARTICIPANT_READER
      || *reader_id == EntityId::P2P_BUILTIN_PARTICIPANT_MESSAGE_READER
    {
      STANDARD_BUILTIN_READERS_INIT_LIST[i].3.clone()
    } else {
      Discovery::builtin_sedp_reader_qos()
    };
    let mut r = reader(&dds_cache, *reader_id, &format!("builtin{i}"), qos.clone());
    for w in writers.into_iter().flatten().filter(|w| w.entity_id == *writer_id) {
      matched(&mut r, *w, &qos);
    }
    receiver.add_reader(r);
  }
  if let Some(named) = &named {
    let qos = QosPolicyBuilder::new()
      .reliability(policy::Reliability::Reliable {
        max_blocking_time: crate::Duration::from_millis(10),
      })
      .history(policy::History::KeepAll)
      .build();
    for (i, id) in named.user_readers.iter().enumerate() {
      let mut r = reader(&dds_cache, *id, &format!("user{i}"), qos.clone());
      for w in named.writers.iter().filter(|w| w.entity_id.kind().is_user_defined()) {
        matched(&mut r, *w, &qos);
      }
      receiver.add_reader(r);
    }
  }

  receiver.handle_received_packet(&bytes, PacketOrigin::UNKNOWN);

  // Discovery reads the built-in topics' samples: the same deserializers on
  // the same payloads.
  for sub in parsed.iter().flat_map(|m| &m.submessages) {
    let SubmessageBody::Writer(WriterSubmessage::Data(data, _)) = &sub.body else {
      continue;
    };
    let Some(payload) = data
      .serialized_payload
      .as_ref()
      .and_then(|p| SerializedPayload::from_bytes(p).ok())
    else {
      continue;
    };
    let (value, repr) = (&payload.value[..], payload.representation_identifier);
    match data.writer_id {
      EntityId::SPDP_BUILTIN_PARTICIPANT_WRITER => {
        let _ = SpdpDiscoveredParticipantData::from_pl_cdr_bytes(value, repr);
      }
      EntityId::SEDP_BUILTIN_PUBLICATIONS_WRITER => {
        let _ = DiscoveredWriterData::from_pl_cdr_bytes(value, repr);
      }
      EntityId::SEDP_BUILTIN_SUBSCRIPTIONS_WRITER => {
        let _ = DiscoveredReaderData::from_pl_cdr_bytes(value, repr);
      }
      EntityId::SEDP_BUILTIN_TOPIC_WRITER => {
        let _ = DiscoveredTopicData::from_pl_cdr_bytes(value, repr);
      }
      _ => {}
    }
  }
}
