// touch_wall in C#: what examples/touch_wall/main.cpp does, over the C# client (Hapticd, the
// Unity package's runtime, which speaks to hapticd's HTTP face: host:port is that face's,
// hapticd --http-api PORT), printing the same lines. It registers a wall (the half-space z < 0)
// and a weak spring field, has the server's simulated hand push the tool into the wall, and prints
// time, hand target, tool height and force at about 20 Hz. On a device with no simulated hand it
// renders the same wall and prints what the tool does for --seconds.
//
// Usage: mono touch_wall.exe [host:port] [--lockstep] [--hand] [--seconds S]
//                            [--token T | --token-file F] [--ca CA.pem [--cert C.pem --key K.pem]
//                            [--server-name NAME]]
using System;
using System.IO;
using System.Numerics;
using System.Text;
using System.Threading;
using Hapticd;

static class TouchWall
{
    const double StartZ = 0.02;        // hand target at the start. Unit: m.
    const double EndZ = -0.01;         // 10 mm below the wall's surface. Unit: m.
    const double Descent = 2.0;        // Unit: s.
    const double Hold = 1.0;           // Unit: s.
    const double HandStiffness = 200.0;  // Unit: N/m.
    const double HandDamping = 2.0;      // Unit: N·s/m.
    const string Usage = "touch_wall [host:port] [--lockstep] [--hand] [--seconds S] [--token T | --token-file F] " +
                         "[--ca CA.pem [--cert C.pem --key K.pem] [--server-name NAME]]";

    static double TargetAt(double t)
    {
        double s = t < Descent ? t / Descent : 1.0;
        return StartZ + s * (EndZ - StartZ);
    }

    static void PrintRow(double t, double target, State state)
    {
        Console.Write(Printf.F(t, 7, 3) + "  " + Printf.F(target * 1e3, 10, 2) + "  " + Printf.F(state.Position.Z * 1e3, 8, 3) +
                      "  " + Printf.F(state.Force.Z, 9, 3) + "  " + (state.ContactCount > 0 ? "yes" : "no") + "\n");
    }

    static void PrintHandRow(double t, State state)
    {
        Console.Write(Printf.F(t, 7, 3) + "  " + "-".PadLeft(10) + "  " + Printf.F(state.Position.Z * 1e3, 8, 3) +
                      "  " + Printf.F(state.Force.Z, 9, 3) + "  " + (state.ContactCount > 0 ? "yes" : "no") + "\n");
    }

    static void PrintHeader()
    {
        Console.Write("time_s".PadLeft(7) + "  " + "target_mm".PadLeft(10) + "  " + "z_mm".PadLeft(8) + "  " +
                      "force_N".PadLeft(9) + "  contact\n");
    }

    static int UsageError(string why)
    {
        Console.Error.Write("touch_wall: " + why + "\nusage: " + Usage + "\n");
        return 2;
    }

    static volatile bool interrupted;

    static int Main(string[] args)
    {
        // The same bytes as the C++ program: "\n" line ends, output flushed at exit.
        var stdout = new StreamWriter(Console.OpenStandardOutput(), new UTF8Encoding(false)) { AutoFlush = false, NewLine = "\n" };
        var stderr = new StreamWriter(Console.OpenStandardError(), new UTF8Encoding(false)) { AutoFlush = true, NewLine = "\n" };
        Console.SetOut(stdout);
        Console.SetError(stderr);
        try { return Run(args); }
        finally { stdout.Flush(); }
    }

    static int Run(string[] args)
    {
        string address = "127.0.0.1:8081";  // hapticd --http-api 8081
        bool lockstep = false, hand = false;
        double seconds = 10.0;
        var config = new ClientConfig();
        string tokenFile = null;
        for (int i = 0; i < args.Length; ++i)
        {
            string arg = args[i];
            string value = i + 1 < args.Length ? args[i + 1] : null;
            if (arg == "--lockstep") lockstep = true;
            else if (arg == "--hand") hand = true;
            else if (arg == "--seconds")
            {
                if (value == null) return UsageError("--seconds needs a number");
                ++i;
                if (!double.TryParse(value, System.Globalization.NumberStyles.Float, System.Globalization.CultureInfo.InvariantCulture, out seconds) ||
                    !(seconds > 0.0 && seconds <= 3600.0))
                {
                    return UsageError("--seconds: '" + value + "' is not a time of 0 to 3600 s");
                }
            }
            else if (arg == "--token") { if (value == null) return UsageError("--token needs the token"); config.Token = args[++i]; }
            else if (arg == "--token-file") { if (value == null) return UsageError("--token-file needs a file"); tokenFile = args[++i]; }
            else if (arg == "--ca") { if (value == null) return UsageError("--ca needs a PEM file"); config.TlsCaFile = args[++i]; }
            else if (arg == "--cert") { if (value == null) return UsageError("--cert needs a PEM file"); config.TlsCertFile = args[++i]; }
            else if (arg == "--key") { if (value == null) return UsageError("--key needs a PEM file"); config.TlsKeyFile = args[++i]; }
            else if (arg == "--server-name") { if (value == null) return UsageError("--server-name needs a name"); config.TlsServerName = args[++i]; }
            else if (arg == "--help" || arg == "-h") { Console.Write("usage: " + Usage + "\n"); return 0; }
            else if (arg.StartsWith("--")) return UsageError("unknown option " + arg);
            else address = arg;
        }
        if (tokenFile != null)
        {
            try
            {
                using (var reader = new StreamReader(tokenFile))
                {
                    config.Token = reader.ReadLine();
                    if (config.Token == null) return UsageError("--token-file: cannot read '" + tokenFile + "'");
                }
            }
            catch (IOException) { return UsageError("--token-file: cannot read '" + tokenFile + "'"); }
        }
        if (config.TlsCaFile == "" && (config.TlsCertFile != "" || config.TlsKeyFile != "" || config.TlsServerName != ""))
        {
            return UsageError("--cert, --key and --server-name need --ca (TLS)");
        }
        try
        {
            config.ServerAddress = address;
            config.ClientName = "touch_wall";
            using (var client = new Client(config))
            {
                var info = client.DeviceInfo;
                double rate = info.LoopRateHz;
                var ticksPerRow = (uint)(rate / 20.0);  // ~20 Hz output
                client.Subscribe(ticksPerRow);
                var wallSpec = WallSpec.Default;
                wallSpec.Impedance = new Impedance(1000.0, 1.0);
                var wall = client.AddWall(wallSpec);
                if (hand || !info.Simulated)
                {
                    return Watch(client, info, lockstep, seconds, ticksPerRow);
                }
                var springSpec = SpringFieldSpec.Default;
                springSpec.Anchor = new Vec3(0, 0, StartZ);
                springSpec.Stiffness = 20.0;
                springSpec.MaxForce = 2.0;
                var spring = client.AddField(springSpec);
                Console.Write("touch_wall: " + info.Name + " at " + Printf.F(rate, 0, 0) + " Hz, " +
                              (lockstep ? "lockstep" : "real") + " time; wall z < 0 with K = 1000 N/m, B = 1 N*s/m\n");
                PrintHeader();
                const double duration = Descent + Hold;
                State state;
                ulong lastTick = 0;
                if (lockstep)
                {
                    // 10 ms steps, moving the hand's target between them; rows timed from the first step.
                    uint perStep = Math.Max(1u, (uint)(rate / 100.0));
                    ulong? firstTick = null;
                    ulong nextRowTick = 0;
                    double t = 0.0;
                    while (t < duration)
                    {
                        double target = TargetAt(t);
                        client.SetOperator(OperatorInput.Follow(new Vec3(0, 0, target), HandStiffness, HandDamping));
                        ulong tick = client.Step(perStep);
                        lastTick = tick;
                        if (firstTick == null)
                        {
                            firstTick = tick;
                            nextRowTick = tick;
                        }
                        t = (double)(tick - firstTick.Value + perStep) / rate;
                        if (tick >= nextRowTick && client.WaitForTick(tick, out state, 2000))
                        {
                            PrintRow(t, target, state);
                            nextRowTick = tick + ticksPerRow;
                        }
                    }
                }
                else
                {
                    long start = Client.SteadyClockNs();
                    long nextUpdate = start;
                    double t = 0.0, firstServerTime = -1.0;
                    while (t < duration)
                    {
                        t = (Client.SteadyClockNs() - start) * 1e-9;
                        client.SetOperator(OperatorInput.Follow(new Vec3(0, 0, TargetAt(t)), HandStiffness, HandDamping));
                        if (client.PollState(out state, 0))
                        {
                            if (firstServerTime < 0) firstServerTime = state.ServerTime;
                            PrintRow(state.ServerTime - firstServerTime, TargetAt(t), state);
                        }
                        nextUpdate += 10000000;
                        long left = nextUpdate - Client.SteadyClockNs();
                        if (left > 0) Thread.Sleep(TimeSpan.FromTicks(left / 100));
                    }
                }
                client.SetOperator(OperatorInput.Release());
                if (lockstep)
                {
                    // Only what lockstep makes exact: the datagrams received depend on the network's timing.
                    Console.Write("touch_wall: done; server at tick " + lastTick + "\n");
                }
                else
                {
                    try
                    {
                        var stats = client.Stats();
                        Console.Write("touch_wall: done; server loop " + Printf.F(stats.Counters.AchievedRateHz, 0, 1) +
                                      " Hz, lateness p99 " + Printf.F(stats.Counters.LatenessP99Us, 0, 0) + " us, " +
                                      client.ReceiveCounters.Accepted + " datagrams received\n");
                    }
                    catch (HapticException e)
                    {
                        if (e.Code != ErrorCode.PermissionDenied) throw;  // the loop's figures are an ADMIN's
                        Console.Write("touch_wall: done; " + client.ReceiveCounters.Accepted + " datagrams received\n");
                    }
                }
                spring.Release();  // they go with the session
                wall.Release();
            }
        }
        catch (HapticException e)
        {
            if (e.Code == ErrorCode.Connection)
            {
                // Starting a server is the fix only when nothing listens; a TLS or token mismatch says its own.
                bool nothingListens = e.Message.Contains("nothing listens");
                Console.Error.Write("touch_wall: " + e.Message + (nothingListens ? ". Start one with ./scripts/run" : "") + "\n");
                return 1;
            }
            Console.Error.Write("touch_wall: " + e.Message + "\n");
            return e.Code == ErrorCode.InvalidArgument ? 2 : 1;
        }
        return 0;
    }

    /// The device's own hand (or a person's): print what the tool does for `seconds`.
    static int Watch(Client client, DeviceInfo info, bool lockstep, double seconds, uint ticksPerRow)
    {
        double rate = info.LoopRateHz;
        Console.CancelKeyPress += (sender, e) => { e.Cancel = true; interrupted = true; };
        Console.Write("touch_wall: " + info.Name + " at " + Printf.F(rate, 0, 0) + " Hz, " + (lockstep ? "lockstep" : "real") +
                      " time, " + (info.Simulated ? "the simulated hand left still" : "no simulated hand") +
                      "; wall z < 0 with K = 1000 N/m, B = 1 N*s/m: push the tool down into it (" +
                      Printf.F(seconds, 0, 0) + " s, Ctrl-C ends)\n");
        PrintHeader();
        State state = new State();
        double deepestMm = 0.0, strongestN = 0.0;
        Action<double> note = t =>
        {
            PrintHandRow(t, state);
            deepestMm = Math.Min(deepestMm, state.Position.Z * 1e3);
            strongestN = Math.Max(strongestN, state.Force.Z);
        };
        if (lockstep)  // the device's own dynamics, stepped: the same rows on every run
        {
            uint perStep = Math.Max(1u, (uint)(rate / 100.0));
            ulong? firstTick = null;
            ulong nextRowTick = 0;
            for (double t = 0.0; !interrupted && t < seconds;)
            {
                ulong tick = client.Step(perStep);
                if (firstTick == null)
                {
                    firstTick = tick;
                    nextRowTick = tick;
                }
                t = (double)(tick - firstTick.Value + perStep) / rate;
                if (tick >= nextRowTick && client.WaitForTick(tick, out state, 2000))
                {
                    note(t);
                    nextRowTick = tick + ticksPerRow;
                }
            }
        }
        else
        {
            double firstServerTime = -1.0;
            long end = Client.SteadyClockNs() + (long)(seconds * 1e9);
            while (!interrupted && Client.SteadyClockNs() < end)
            {
                if (!client.PollState(out state, 100)) continue;
                if (firstServerTime < 0) firstServerTime = state.ServerTime;
                note(state.ServerTime - firstServerTime);
            }
        }
        Console.Write("touch_wall: done; deepest " + Printf.F(-deepestMm, 0, 3) + " mm into the wall, largest push back " +
                      Printf.F(strongestN, 0, 3) + " N, " + client.ReceiveCounters.Accepted + " datagrams received\n");
        return 0;
    }
}

/// printf's "%*.*f": the double's exact binary value rounded half to even at `decimals`, with the
/// sign kept for a negative value that rounds to zero, as glibc prints it (.NET's "F" formats
/// differ in both on some runtimes).
static class Printf
{
    public static string F(double value, int width, int decimals)
    {
        if (double.IsNaN(value)) return (BitConverter.DoubleToInt64Bits(value) < 0 ? "-nan" : "nan").PadLeft(width);
        if (double.IsInfinity(value)) return (value < 0 ? "-inf" : "inf").PadLeft(width);
        long bits = BitConverter.DoubleToInt64Bits(value);
        bool negative = bits < 0;
        int exponent = (int)((bits >> 52) & 0x7FF);
        long fraction = bits & 0xFFFFFFFFFFFFFL;
        BigInteger mantissa = exponent == 0 ? fraction : fraction | (1L << 52);
        int power = (exponent == 0 ? 1 : exponent) - 1075;  // value = mantissa × 2^power
        // scaled = |value| × 10^decimals = numerator / denominator, exactly.
        BigInteger numerator = mantissa * BigInteger.Pow(10, decimals);
        BigInteger denominator = BigInteger.One;
        if (power >= 0) numerator <<= power; else denominator <<= -power;
        BigInteger remainder;
        BigInteger quotient = BigInteger.DivRem(numerator, denominator, out remainder);
        BigInteger twice = remainder * 2;
        if (twice > denominator || (twice == denominator && !quotient.IsEven)) quotient += 1;
        string digits = quotient.ToString().PadLeft(decimals + 1, '0');
        string text = decimals > 0 ? digits.Substring(0, digits.Length - decimals) + "." + digits.Substring(digits.Length - decimals) : digits;
        return ((negative ? "-" : "") + text).PadLeft(width);
    }
}
