// A Sparkplug B 3.0 primary host for the interop tests, built on Eclipse Tahu
// 1.0.21 (tahu-core, EPL-2.0) and Eclipse Paho mqttv3: every message under
// spBv1.0/# is decoded with Tahu's SparkplugBPayloadDecoder and printed as one
// JSON line; commands come on stdin, one a line:
//   state online|offline                      STATE on spBv1.0/STATE/<host> (retained, QoS 1)
//   rebirth <group> <edge>                    NCMD with Node Control/Rebirth = true
//   dcmd <group> <edge> <device> <metric> <type> <value>
//                                             DCMD with one metric of a Tahu MetricDataType
//   quit                                      STATE offline, disconnect, exit 0
// Usage: java -cp build:lib/* TahuHost <broker url> <host id>
// Output lines: {"ready":true}, {"sent":"<command>"}, {"topic":...,"type":...,...},
// {"error":"..."}. 64-bit integers are printed as JSON strings (a JavaScript
// number cannot hold every one), DateTime as milliseconds since the epoch.
import java.io.BufferedReader;
import java.io.InputStreamReader;
import java.lang.reflect.Array;
import java.math.BigInteger;
import java.nio.charset.StandardCharsets;
import java.util.ArrayList;
import java.util.Date;
import java.util.HashMap;
import java.util.List;
import java.util.Map;
import org.eclipse.paho.client.mqttv3.IMqttDeliveryToken;
import org.eclipse.paho.client.mqttv3.MqttCallback;
import org.eclipse.paho.client.mqttv3.MqttClient;
import org.eclipse.paho.client.mqttv3.MqttConnectOptions;
import org.eclipse.paho.client.mqttv3.MqttMessage;
import org.eclipse.paho.client.mqttv3.persist.MemoryPersistence;
import org.eclipse.tahu.message.SparkplugBPayloadDecoder;
import org.eclipse.tahu.message.SparkplugBPayloadEncoder;
import org.eclipse.tahu.message.model.DataSet;
import org.eclipse.tahu.message.model.DataSetDataType;
import org.eclipse.tahu.message.model.Metric;
import org.eclipse.tahu.message.model.MetricDataType;
import org.eclipse.tahu.message.model.SparkplugBPayload;
import org.eclipse.tahu.model.MetricDataTypeMap;

public final class TahuHost {
  private static final Object OUT = new Object();
  /** Per edge node (group/edge): the datatypes its births gave each alias, for Tahu's decoder. */
  private static final Map<String, MetricDataTypeMap> TYPES = new HashMap<>();
  /** Per edge node: the names its births gave each alias. */
  private static final Map<String, Map<Long, String>> NAMES = new HashMap<>();

  private TahuHost() {}

  public static void main(String[] args) throws Exception {
    if (args.length != 2) {
      System.err.println("usage: TahuHost <broker url> <host id>");
      System.exit(2);
    }
    String host = args[1];
    String stateTopic = "spBv1.0/STATE/" + host;
    long birth = System.currentTimeMillis();
    MqttClient client = new MqttClient(args[0], "tahu-" + host + "-" + birth, new MemoryPersistence());
    MqttConnectOptions options = new MqttConnectOptions();
    options.setCleanSession(true);
    options.setAutomaticReconnect(false);
    options.setKeepAliveInterval(30);
    // Sparkplug 3.0: the host's Will is its STATE offline, retained, QoS 1,
    // with the timestamp of the birth it ends.
    options.setWill(stateTopic, state(false, birth), 1, true);
    client.setCallback(
        new MqttCallback() {
          @Override
          public void connectionLost(Throwable cause) {
            print("{\"error\":" + quote("connection lost: " + cause) + "}");
          }

          @Override
          public void messageArrived(String topic, MqttMessage message) {
            print(describe(topic, message));
          }

          @Override
          public void deliveryComplete(IMqttDeliveryToken token) {}
        });
    client.connect(options);
    client.subscribe("spBv1.0/#", 1);
    client.publish(stateTopic, state(true, birth), 1, true);
    print("{\"ready\":true}");

    BufferedReader in = new BufferedReader(new InputStreamReader(System.in, StandardCharsets.UTF_8));
    String line;
    while ((line = in.readLine()) != null) {
      line = line.trim();
      if (line.isEmpty()) continue;
      String[] w = line.split(" ", 7);
      try {
        if (w[0].equals("quit")) break;
        else if (w[0].equals("state")) {
          birth = System.currentTimeMillis();
          client.publish(stateTopic, state(w[1].equals("online"), birth), 1, true);
        } else if (w[0].equals("rebirth")) {
          Metric m = new Metric("Node Control/Rebirth", null, new Date(), MetricDataType.Boolean, null, null, null, null, true);
          send(client, "spBv1.0/" + w[1] + "/NCMD/" + w[2], m);
        } else if (w[0].equals("dcmd")) {
          MetricDataType type = dataType(w[5]);
          Metric m = new Metric(w[4], null, new Date(), type, null, null, null, null, parse(type, w[6]));
          send(client, "spBv1.0/" + w[1] + "/DCMD/" + w[2] + "/" + w[3], m);
        } else throw new IllegalArgumentException("unknown command " + w[0]);
        print("{\"sent\":" + quote(line) + "}");
      } catch (Exception e) {
        print("{\"error\":" + quote(line + ": " + e) + "}");
      }
    }
    client.publish(stateTopic, state(false, birth), 1, true);
    client.disconnect();
    client.close();
    System.exit(0);
  }

  private static byte[] state(boolean online, long timestamp) {
    return ("{\"online\":" + online + ",\"timestamp\":" + timestamp + "}").getBytes(StandardCharsets.UTF_8);
  }

  private static void send(MqttClient client, String topic, Metric metric) throws Exception {
    SparkplugBPayload payload = new SparkplugBPayload(new Date(), new ArrayList<>(List.of(metric)));
    client.publish(topic, new SparkplugBPayloadEncoder().getBytes(payload, false), 0, false);
  }

  /** Tahu's MetricDataType named `name` (Int8, UInt64, DateTime, ...). */
  private static MetricDataType dataType(String name) {
    for (int i = 1; i <= 34; i++) {
      MetricDataType t = MetricDataType.fromInteger(i);
      if (t.getType().equals(name)) return t;
    }
    throw new IllegalArgumentException("no Sparkplug datatype " + name);
  }

  /** A command's value as the Java class Tahu's encoder takes for `type`. */
  private static Object parse(MetricDataType type, String text) {
    switch (type.getType()) {
      case "Int8":
        return Byte.parseByte(text);
      case "Int16":
      case "UInt8":
        return Short.parseShort(text);
      case "Int32":
      case "UInt16":
        return Integer.parseInt(text);
      case "Int64":
      case "UInt32":
        return Long.parseLong(text);
      case "UInt64":
        return new BigInteger(text);
      case "Float":
        return Float.parseFloat(text);
      case "Double":
        return Double.parseDouble(text);
      case "Boolean":
        return Boolean.parseBoolean(text);
      case "DateTime":
        return new Date(Long.parseLong(text));
      case "String":
      case "Text":
        return text;
      default:
        throw new IllegalArgumentException("no command value for type " + type);
    }
  }

  private static String describe(String topic, MqttMessage message) {
    String[] t = topic.split("/");
    StringBuilder b = new StringBuilder("{\"topic\":").append(quote(topic));
    if (t.length >= 3 && t[1].equals("STATE")) {
      return b.append(",\"type\":\"STATE\",\"retained\":")
          .append(message.isRetained())
          .append(",\"json\":")
          .append(quote(new String(message.getPayload(), StandardCharsets.UTF_8)))
          .append('}')
          .toString();
    }
    if (t.length < 4) return b.append(",\"error\":\"not a Sparkplug B topic\"}").toString();
    String type = t[2];
    String node = t[1] + "/" + t[3];
    b.append(",\"type\":").append(quote(type)).append(",\"group\":").append(quote(t[1]));
    b.append(",\"edge\":").append(quote(t[3]));
    if (t.length > 4) b.append(",\"device\":").append(quote(t[4]));
    b.append(",\"qos\":").append(message.getQos()).append(",\"retained\":").append(message.isRetained());
    try {
      if (type.equals("NBIRTH")) {
        TYPES.put(node, new MetricDataTypeMap());
        NAMES.put(node, new HashMap<>());
      }
      MetricDataTypeMap types = TYPES.computeIfAbsent(node, k -> new MetricDataTypeMap());
      Map<Long, String> names = NAMES.computeIfAbsent(node, k -> new HashMap<>());
      SparkplugBPayload p = new SparkplugBPayloadDecoder().buildFromByteArray(message.getPayload(), types);
      boolean birth = type.endsWith("BIRTH");
      if (p.getSeq() != null) b.append(",\"seq\":").append(p.getSeq());
      if (p.getTimestamp() != null) b.append(",\"timestamp\":").append(p.getTimestamp().getTime());
      b.append(",\"metrics\":[");
      String sep = "";
      for (Metric m : p.getMetrics()) {
        if (m == null) throw new IllegalStateException("Tahu's decoder returned no metric (see its log)");
        if (birth && m.hasAlias()) {
          types.addMetricDataType(m.getAlias(), m.getDataType());
          names.put(m.getAlias(), m.getName());
        }
        if ("bdSeq".equals(m.getName())) b.insert(b.indexOf(",\"metrics\""), ",\"bdSeq\":" + json(m.getValue()));
        b.append(sep).append(metric(m, names));
        sep = ",";
      }
      return b.append("]}").toString();
    } catch (Exception e) {
      return b.append(",\"error\":").append(quote("Tahu could not decode it: " + e)).append('}').toString();
    }
  }

  private static String metric(Metric m, Map<Long, String> names) {
    StringBuilder b = new StringBuilder("{");
    String name = m.getName() != null ? m.getName() : m.hasAlias() ? names.get(m.getAlias()) : null;
    b.append("\"name\":").append(name == null ? "null" : quote(name));
    b.append(",\"named\":").append(m.hasName());
    if (m.hasAlias()) b.append(",\"alias\":").append(m.getAlias());
    b.append(",\"datatype\":").append(quote(String.valueOf(m.getDataType())));
    b.append(",\"value\":").append(json(m.getValue()));
    if (m.getTimestamp() != null) b.append(",\"timestamp\":").append(m.getTimestamp().getTime());
    b.append(",\"is_historical\":").append(Boolean.TRUE.equals(m.getIsHistorical()));
    b.append(",\"is_null\":").append(Boolean.TRUE.equals(m.getIsNull()));
    return b.append('}').toString();
  }

  private static String json(Object v) {
    if (v == null) return "null";
    if (v instanceof DataSet) {
      // A DataSet as Tahu decoded it: its column names, the types it read, and each row's cells.
      DataSet d = (DataSet) v;
      StringBuilder b = new StringBuilder("{\"columns\":[");
      String sep = "";
      for (String c : d.getColumnNames()) { b.append(sep).append(quote(c)); sep = ","; }
      b.append("],\"types\":[");
      sep = "";
      for (DataSetDataType t : d.getTypes()) { b.append(sep).append(quote(String.valueOf(t))); sep = ","; }
      b.append("],\"rows\":[");
      sep = "";
      for (List<Object> row : d.getRowsAsLists()) { b.append(sep).append(json(row.toArray())); sep = ","; }
      return b.append("]}").toString();
    }
    if (v instanceof Long || v instanceof BigInteger) return quote(v.toString());
    if (v instanceof Number || v instanceof Boolean) return v.toString();
    if (v instanceof Date) return Long.toString(((Date) v).getTime());
    if (v.getClass().isArray()) {
      StringBuilder b = new StringBuilder("[");
      for (int i = 0; i < Array.getLength(v); i++) b.append(i > 0 ? "," : "").append(json(Array.get(v, i)));
      return b.append(']').toString();
    }
    return quote(v.toString());
  }

  private static String quote(String s) {
    StringBuilder b = new StringBuilder("\"");
    for (char c : s.toCharArray()) {
      if (c == '"' || c == '\\') b.append('\\').append(c);
      else if (c < 0x20) b.append(String.format("\\u%04x", (int) c));
      else b.append(c);
    }
    return b.append('"').toString();
  }

  private static void print(String line) {
    synchronized (OUT) {
      System.out.println(line);
      System.out.flush();
    }
  }
}
