// Apache PLC4X 0.13.1 (plc4j, Apache-2.0) as an interoperability peer of the
// plcwire simulator: connects with the connection string it is given (the
// driver's defaults unless the string says otherwise), then writes and reads
// the tags it is given, in order, in one request each, and prints one JSON
// line per tag: {"op":"read"|"write","tag":…,"code":…,"value":…}.
// Driven by test/interop/plc4x-vs-server.test.js; built by
// test/support/install-peers.js (javac against the jars in lib/).
//
// Usage: java -cp 'build:lib/*' Plc4xPeer <connection string> [w:<tag>=<value>]... [r:<tag>]... [c:<ms>:<tag>]...
// c:<ms>:<tag> subscribes a cyclic-data tag (CYC(<time base>:<factor>):<address>, S7-300/400) for <ms> ms
// and prints {"op":"cyclic","tag":…,"code":…} for the subscription, then {"op":"event",…,"value":…} per push.
// s:<tag>[,<tag>]... sends one subscription request with those event tags (MODE, SYS, USR, ALM, QUERY:ALARM_S,
// ACK:16#<event id>; S7-300/400, issue #33), prints {"op":"subscribe","tag":<name>,"code":…} per name in the answer,
// then {"op":"event","tag":<tag>,"code":"OK","value":<the event's map>} per event of a MODE/SYS/USR/ALM handle.
// An argument "-" reads further operations from stdin, one a line, each answered by {"op":"done","tag":<op>}, until EOF.
// A value is converted after the tag's type (the text after its last ':').
// Exit 0 when every request got an answer (each tag's code says whether it was
// OK), 3 when the connection or a request failed (the message on stderr).
import java.math.BigInteger;
import java.time.Duration;
import java.time.LocalDate;
import java.time.LocalDateTime;
import java.time.LocalTime;
import java.io.BufferedReader;
import java.io.InputStreamReader;
import java.nio.charset.StandardCharsets;
import java.util.TreeMap;
import java.util.concurrent.TimeUnit;
import org.apache.plc4x.java.DefaultPlcDriverManager;
import org.apache.plc4x.java.api.PlcConnection;
import org.apache.plc4x.java.api.messages.PlcReadRequest;
import org.apache.plc4x.java.api.messages.PlcReadResponse;
import org.apache.plc4x.java.api.messages.PlcSubscriptionRequest;
import org.apache.plc4x.java.api.messages.PlcSubscriptionResponse;
import org.apache.plc4x.java.api.messages.PlcWriteRequest;
import org.apache.plc4x.java.api.messages.PlcWriteResponse;
import org.apache.plc4x.java.api.value.PlcValue;
import org.apache.plc4x.java.s7.events.S7Event;

public final class Plc4xPeer {
  private static final long TIMEOUT_S = 10;

  public static void main(String[] args) {
    if (args.length < 1) {
      System.err.println("usage: Plc4xPeer <connection string> [w:<tag>=<value>]... [r:<tag>]...");
      System.exit(2);
    }
    try (PlcConnection connection = new DefaultPlcDriverManager().getConnection(args[0])) {
      for (int i = 1; i < args.length; i++) {
        if ("-".equals(args[i])) {
          BufferedReader in = new BufferedReader(new InputStreamReader(System.in, StandardCharsets.UTF_8));
          for (String line = in.readLine(); line != null; line = in.readLine()) {
            if (line.isEmpty()) continue;
            run(connection, line);
            print("done", line, "OK", null);
          }
        } else {
          run(connection, args[i]);
        }
      }
    } catch (Exception e) {
      System.err.println(e.getClass().getSimpleName() + ": " + e.getMessage());
      System.exit(3);
    }
    System.exit(0);
  }

  private static void run(PlcConnection connection, String op) throws Exception {
    if (op.startsWith("c:")) {
      cyclic(connection, op.substring(2));
      return;
    }
    if (op.startsWith("s:")) {
      events(connection, op.substring(2).split(","));
      return;
    }
    if (op.startsWith("r:")) {
      String tag = op.substring(2);
      PlcReadRequest request = connection.readRequestBuilder().addTagAddress("t", tag).build();
      PlcReadResponse response = request.execute().get(TIMEOUT_S, TimeUnit.SECONDS);
      String code = response.getResponseCode("t").name();
      PlcValue value = "OK".equals(code) ? response.getPlcValue("t") : null;
      print("read", tag, code, value == null ? null : text(value));
    } else if (op.startsWith("w:")) {
      int eq = op.indexOf('=');
      String tag = op.substring(2, eq);
      Object value = parse(tag, op.substring(eq + 1));
      PlcWriteRequest request = connection.writeRequestBuilder().addTagAddress("t", tag, value).build();
      PlcWriteResponse response = request.execute().get(TIMEOUT_S, TimeUnit.SECONDS);
      print("write", tag, response.getResponseCode("t").name(), null);
    } else {
      throw new IllegalArgumentException("not r:<tag> or w:<tag>=<value>: " + op);
    }
  }

  /** A cyclic subscription (issue #33): "<ms>:<tag>"; every event's value of the tag, until <ms> ms have passed. */
  private static void cyclic(PlcConnection connection, String spec) throws Exception {
    int colon = spec.indexOf(':');
    long ms = Long.parseLong(spec.substring(0, colon));
    String tag = spec.substring(colon + 1);
    PlcSubscriptionRequest request = connection.subscriptionRequestBuilder().addEventTagAddress("t", tag).build();
    PlcSubscriptionResponse response = request.execute().get(TIMEOUT_S, TimeUnit.SECONDS);
    String code = response.getResponseCode("t").name();
    print("cyclic", tag, code, null);
    if (!"OK".equals(code)) return;
    // S7CyclicEvent answers getTagNames() with UnsupportedOperationException in 0.13.1: its map holds the values.
    response
        .getSubscriptionHandle("t")
        .register(e -> print("event", tag, "OK", String.valueOf(((S7Event) e).getMap().get("t"))));
    Thread.sleep(ms);
  }

  /** One subscription request of event tags (issue #33): the answer's code per name, then each event of the handles. */
  private static void events(PlcConnection connection, String[] tags) throws Exception {
    PlcSubscriptionRequest.Builder builder = connection.subscriptionRequestBuilder();
    for (String tag : tags) builder.addEventTagAddress(tag, tag);
    PlcSubscriptionResponse response = builder.build().execute().get(TIMEOUT_S, TimeUnit.SECONDS);
    for (String name : response.getTagNames()) {
      String code = response.getResponseCode(name).name();
      print("subscribe", name, code, null);
      if (!"OK".equals(code) || !name.matches("MODE|SYS|USR|ALM")) continue;
      response.getSubscriptionHandle(name).register(e -> print("event", name, "OK", String.valueOf(new TreeMap<>(((S7Event) e).getMap()))));
    }
  }

  /** The value as text: an ISO form for times, the number or string for the rest. */
  private static String text(PlcValue value) {
    Object o = value.getObject();
    return String.valueOf(o);
  }

  /** The Java value PLC4X expects for the tag's type (after its last ':', without a [n] count). */
  private static Object parse(String tag, String text) {
    String type = tag.substring(tag.lastIndexOf(':') + 1).replaceAll("\\[.*$", "");
    switch (type) {
      case "BOOL":
        return Boolean.parseBoolean(text);
      case "BYTE":
      case "USINT":
      case "SINT":
        return Short.parseShort(text);
      case "WORD":
      case "UINT":
      case "INT":
        return Integer.parseInt(text);
      case "DWORD":
      case "UDINT":
      case "DINT":
        return Long.parseLong(text);
      case "LWORD":
      case "ULINT":
      case "LINT":
        return new BigInteger(text);
      case "REAL":
        return Float.parseFloat(text);
      case "LREAL":
        return Double.parseDouble(text);
      case "TIME":
      case "LTIME":
        return Duration.parse(text);
      case "DATE":
        return LocalDate.parse(text);
      case "TIME_OF_DAY":
      case "TOD":
        return LocalTime.parse(text);
      case "DATE_AND_TIME":
      case "DT":
        return LocalDateTime.parse(text);
      default:
        return text; // CHAR, WCHAR, STRING, WSTRING
    }
  }

  private static synchronized void print(String op, String tag, String code, String value) {
    StringBuilder b = new StringBuilder();
    b.append("{\"op\":\"").append(op).append("\",\"tag\":").append(quote(tag)).append(",\"code\":\"").append(code).append('"');
    if (value != null) b.append(",\"value\":").append(quote(value));
    System.out.println(b.append('}'));
  }

  private static String quote(String s) {
    StringBuilder b = new StringBuilder("\"");
    for (char c : s.toCharArray()) {
      if (c == '"' || c == '\\') b.append('\\').append(c);
      else if (c < 0x20 || c > 0x7e) b.append(String.format("\\u%04x", (int) c));
      else b.append(c);
    }
    return b.append('"').toString();
  }
}
