// A stand-in for the few UnityEngine types HapticToolFollower uses, written from Unity's public
// scripting reference (docs.unity3d.com/ScriptReference: MonoBehaviour, Transform, Vector3, Debug,
// TooltipAttribute), so that the component compiles and runs under Mono here. Unity itself never
// ran here; its engine calls OnEnable, Update and OnDisable by name, as UnityComponentTest does.
using System;

namespace UnityEngine
{
    public struct Vector3
    {
        public float x, y, z;
        public Vector3(float x, float y, float z) { this.x = x; this.y = y; this.z = z; }
        public static Vector3 operator *(Vector3 v, float s) { return new Vector3(v.x * s, v.y * s, v.z * s); }
        public override string ToString() { return "(" + x + ", " + y + ", " + z + ")"; }
    }

    public class Transform
    {
        public Vector3 position;
    }

    public class Object { }

    public class Component : Object
    {
        private readonly Transform transform_ = new Transform();
        public Transform transform { get { return transform_; } }
    }

    public class Behaviour : Component
    {
        public bool enabled = true;
    }

    public class MonoBehaviour : Behaviour { }

    public static class Debug
    {
        /// Every line logged, for the tests to read: "LogError: …", "LogWarning: …", "Log: …".
        public static readonly System.Collections.Generic.List<string> Logged = new System.Collections.Generic.List<string>();
        public static void LogError(object message) { Write("LogError: " + message); }
        public static void LogWarning(object message) { Write("LogWarning: " + message); }
        public static void Log(object message) { Write("Log: " + message); }
        static void Write(string line) { lock (Logged) Logged.Add(line); Console.Error.WriteLine(line); }
    }

    [AttributeUsage(AttributeTargets.Field)]
    public class TooltipAttribute : Attribute
    {
        public TooltipAttribute(string tooltip) { }
    }
}
