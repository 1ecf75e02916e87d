// HapticToolFollower (the Unity package's component) under Mono with the UnityEngine stand-in,
// against a real lockstep hapticd (first argument): enabled, it opens a session and takes the
// state stream; a second session pushes the tool along W's +y, and the component places its
// transform where the tool is (W's y is Unity's z, scaled), between samples by the binding's
// interpolation; Update runs on the server's clock; disabled, it closes the session. Given an
// address where no server listens, it says so in the console and the scene goes on.
using System;
using System.Reflection;
using System.Threading;
using Hapticd;
using Hapticd.Unity;

static class UnityComponentTest
{
    static int failures;
    static void Check(bool ok, string what) { if (!ok) { failures++; Console.Error.WriteLine("FAIL " + what); } }

    static void Call(object target, string method)
    {
        // Unity calls its messages by name, private or not.
        target.GetType().GetMethod(method, BindingFlags.Instance | BindingFlags.NonPublic | BindingFlags.Public).Invoke(target, null);
    }

    static T Field<T>(object target, string name)
    {
        return (T)target.GetType().GetField(name, BindingFlags.Instance | BindingFlags.NonPublic).GetValue(target);
    }

    static int Main(string[] args)
    {
        var follower = new HapticToolFollower { serverAddress = args[0], clientName = "unity-follower", unitsPerMeter = 10f };
        Call(follower, "OnEnable");
        Check(follower.Client != null, "the component opened a session");
        using (var driver = new Client(new ClientConfig { ServerAddress = args[0], ClientName = "unity-test-driver" }))
        {
            Check(!follower.PlaceAt(0.0), "nothing placed before two samples");
            driver.SetOperator(OperatorInput.Push(new Vec3(0, 0.05, 0)));
            // In steps of 20 ticks, each waited for: the receive thread hands on only the newest of
            // what has queued up, and the component needs two samples.
            ulong tick = 0;
            for (int step = 0; step < 3; ++step)
            {
                tick = driver.Step(20);
                for (int i = 0; i < 500 && Field<State>(follower, "latest_").Tick < tick; ++i) Thread.Sleep(2);
            }
            var a = Field<State>(follower, "previous_");
            var b = Field<State>(follower, "latest_");
            Check(b.Tick == tick && a.Tick < b.Tick, "the two newest samples: " + a.Tick + ", " + b.Tick + " (stepped to " + tick + ")");
            Check(b.Position.Y > 1e-4, "the push moved the tool along W's y: " + b.Position.Y);

            Check(follower.PlaceAt(b.ServerTime), "placed");
            var p = follower.transform.position;
            Check(Math.Abs(p.x - (float)(b.Position.X * 10)) < 1e-5 && Math.Abs(p.y - (float)(b.Position.Z * 10)) < 1e-5 &&
                  Math.Abs(p.z - (float)(b.Position.Y * 10)) < 1e-5, "at the newest sample, W (x, y, z) is Unity (x, z, y) x 10: " + p);
            double middle = 0.5 * (a.ServerTime + b.ServerTime);
            follower.PlaceAt(middle);
            var expected = Motion.Interpolate(a, b, middle);
            Check(Math.Abs(follower.transform.position.z - (float)(expected.Y * 10)) < 1e-5, "between them, the interpolated position");
            Check(follower.transform.position.z < (float)(b.Position.Y * 10), "between them, behind the newest");

            follower.smoothing = HapticToolFollower.Smoothing.Predict;
            follower.PlaceAt(b.ServerTime + 0.01);
            Check(follower.transform.position.z > (float)(b.Position.Y * 10), "predicted ahead of the newest along the push: " +
                  follower.transform.position.z + " vs " + b.Position.Y * 10 + " (v " + b.Velocity.Y + ", previous v " + a.Velocity.Y + ")");

            Call(follower, "Update");  // on the server's clock as the client estimates it
            var q = follower.transform.position;
            Check(!float.IsNaN(q.x) && !float.IsNaN(q.y) && !float.IsNaN(q.z), "Update placed a finite position: " + q);
            Check(driver.Sessions().Length == 2, "two sessions while enabled");
            Call(follower, "OnDisable");
            Check(follower.Client == null && driver.Sessions().Length == 1, "disabled, its session closed");
        }
        var nowhere = new HapticToolFollower { serverAddress = "127.0.0.1:1", clientName = "unity-nowhere" };
        int logged = UnityEngine.Debug.Logged.Count;
        try
        {
            Call(nowhere, "OnEnable");
            Call(nowhere, "Update");
            Call(nowhere, "OnDisable");
        }
        catch (Exception e)
        {
            Check(false, "a connection refused must not throw into the scene: " + e);
        }
        Check(nowhere.Client == null, "no session where no server listens");
        var said = UnityEngine.Debug.Logged.GetRange(logged, UnityEngine.Debug.Logged.Count - logged);
        Check(said.Count == 1 && said[0].StartsWith("LogError: hapticd: cannot connect to 127.0.0.1:1 ("),
              "the refusal said once in the console: " + string.Join(" | ", said));
        Console.WriteLine(failures == 0 ? "the Unity component's checks passed" : failures + " checks failed");
        return failures == 0 ? 0 : 1;
    }
}
