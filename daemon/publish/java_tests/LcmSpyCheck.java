// Decodes every event of an LCM log the way lcm-spy does: the message's first 8 bytes are its
// fingerprint, lcm-spy's LCMTypeDatabase (which scans the CLASSPATH environment variable, as
// lcm-spy does) maps it to a generated class, whose byte[] constructor decodes it. Prints one line
// per event: "EVENT <channel> <class> reencoded|DIFFERENT field=value ...", or
// "EVENT <channel> NO_TYPE <fingerprint>". Exits 1 when any event has no type or does not re-encode
// to the same bytes.
//
//   CLASSPATH=livod_lcmtypes.jar java -cp /usr/share/java/lcm.jar:. LcmSpyCheck LOG
import java.io.ByteArrayInputStream;
import java.io.ByteArrayOutputStream;
import java.io.DataInputStream;
import java.io.DataOutputStream;
import java.io.EOFException;
import java.lang.reflect.Field;
import java.lang.reflect.Modifier;
import java.util.Arrays;
import lcm.lcm.LCMEncodable;
import lcm.logging.Log;
import lcm.spy.LCMTypeDatabase;

public class LcmSpyCheck {
  public static void main(String[] args) throws Exception {
    LCMTypeDatabase types = new LCMTypeDatabase();
    Log log = new Log(args[0], "r");
    int failures = 0;
    while (true) {
      Log.Event event;
      try {
        event = log.readNext();
      } catch (EOFException end) {
        break;
      }
      long fingerprint = new DataInputStream(new ByteArrayInputStream(event.data)).readLong();
      Class<?> type = types.getClassByFingerprint(fingerprint);
      if (type == null) {
        System.out.printf("EVENT %s NO_TYPE %016x%n", event.channel, fingerprint);
        ++failures;
        continue;
      }
      Object message = type.getConstructor(byte[].class).newInstance((Object) event.data);
      ByteArrayOutputStream bytes = new ByteArrayOutputStream();
      ((LCMEncodable) message).encode(new DataOutputStream(bytes));
      boolean same = Arrays.equals(bytes.toByteArray(), event.data);
      if (!same) ++failures;
      StringBuilder line = new StringBuilder("EVENT " + event.channel + " " + type.getName());
      line.append(same ? " reencoded" : " DIFFERENT");
      for (Field field : type.getFields()) {
        if (Modifier.isStatic(field.getModifiers())) continue;
        line.append(' ').append(field.getName()).append('=').append(format(field.get(message)));
      }
      System.out.println(line);
    }
    log.close();
    System.exit(failures == 0 ? 0 : 1);
  }

  // Numbers and strings as Java prints them (spaces replaced by '_'), arrays of numbers in
  // brackets, arrays of nested messages as the list of their `name` fields, byte arrays by length.
  static String format(Object value) throws Exception {
    if (value == null) return "null";
    if (value instanceof double[]) return Arrays.toString((double[]) value).replace(" ", "");
    if (value instanceof double[][]) return Arrays.deepToString((Object[]) value).replace(" ", "");
    if (value instanceof byte[]) return "bytes:" + ((byte[]) value).length;
    if (value instanceof Object[]) {
      StringBuilder names = new StringBuilder("[");
      for (Object element : (Object[]) value) {
        if (names.length() > 1) names.append(',');
        Field name = element.getClass().getField("name");
        names.append(name.get(element));
      }
      return names.append(']').toString();
    }
    if (value instanceof LCMEncodable) return value.getClass().getName();
    return String.valueOf(value).replace(' ', '_');
  }
}
